// AutoRally's 25 basis functions phi[0..24], in order: statements in the common subset of C++
// and GLSL, #included in the body of AutoRallyBasisFunctionModel::basis() (dynamics/
// autorally_bf.hpp) and of its GPU twin bf_basis() (vulkan/shaders/models/autorally_bf.glsl),
// so that both evaluate the one list. Not a header of declarations: no include guard. Reads
// roll, ux, uy, yaw_mder, u1 (the inputs) and moving, inv_ux, su = sin(u0), t = tan(beta - u0),
// t_abs = t |t|, t3 = t^3, q (defined before it by both); `abs` must be the floating-point one.
phi[0] = u1;
phi[1] = ux / 10.f;
phi[2] = su * t / 1200.f;
phi[3] = su * t_abs / 1440000.f;
phi[4] = su * t3 / 1728000000.f;
phi[5] = yaw_mder * uy / 25.f;
phi[6] = yaw_mder / 10.f;
phi[7] = uy / 10.f;
phi[8] = su;
phi[9] = moving ? uy * inv_ux / 40.f : 0.f;
phi[10] = t / 1400.f;
phi[11] = t_abs / 1960000.f;
phi[12] = t3 / 2744000000.f;
phi[13] = q / 40.f;
phi[14] = q * abs(q) / 1600.f;
phi[15] = q * q * q / 64000.f;
phi[16] = yaw_mder * ux / 50.f;
phi[17] = roll;
phi[18] = roll * yaw_mder;
phi[19] = roll * ux / 3.f;
phi[20] = roll * ux * yaw_mder / 5.f;
phi[21] = ux * ux / 100.f;
phi[22] = ux * ux * ux / 1000.f;
phi[23] = u1 * u1;
phi[24] = u1 * u1 * u1;
