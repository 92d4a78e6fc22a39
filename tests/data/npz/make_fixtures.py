#!/usr/bin/python3
"""Writes the tiny .npz fixtures of tests/base/test_npz.cpp (run from this folder with
Debian's /usr/bin/python3 + numpy). The values are simple formulas so the test can check them
without reading numpy: a[i] = ... as noted per array."""
import io
import zipfile

import numpy as np


def npy_bytes(arr, version=None):
    buf = io.BytesIO()
    np.lib.format.write_array(buf, arr, version=version, allow_pickle=False)
    return buf.getvalue()


def write_zip(name, members, compression=zipfile.ZIP_STORED):
    with zipfile.ZipFile(name, "w", compression=compression) as z:
        for key, data in members:
            z.writestr(key, data)


# Deflated float32 (np.savez_compressed): m[i, j] = 10 i + j - 0.5 (2x3), a 0-d scalar 2.5,
# v[i] = 0.1 i (5,) float32, an empty (0,) array.
np.savez_compressed(
    "f32_deflated.npz",
    m=(10 * np.arange(2)[:, None] + np.arange(3)[None, :] - 0.5).astype(np.float32),
    scalar=np.float32(2.5),
    v=(0.1 * np.arange(5)).astype(np.float32),
    empty=np.zeros((0,), np.float32))

# Stored float64 and ints (np.savez): d[i, j] = 1/(1 + i + 2 j) (3x2) float64;
# i4 = [-2, 0, 7] int32; i8 = [-(2**40), 5] int64; u1 = [0, 200, 255] uint8; b1 = [True, False].
np.savez(
    "f64_stored.npz",
    d=1.0 / (1.0 + np.arange(3)[:, None] + 2 * np.arange(2)[None, :]),
    i4=np.array([-2, 0, 7], np.int32),
    i8=np.array([-(2**40), 5], np.int64),
    u1=np.array([0, 200, 255], np.uint8),
    b1=np.array([True, False]))

# .npy format versions 2 and 3 (4-byte header length): w2 = w3 = [1.5, -3.25] float64 (2,).
write_zip("npy_versions.npz", [
    ("w2.npy", npy_bytes(np.array([1.5, -3.25]), version=(2, 0))),
    ("w3.npy", npy_bytes(np.array([1.5, -3.25]), version=(3, 0)))])

# Each of these holds exactly one bad array, "bad".
np.savez("fortran.npz", bad=np.asfortranarray(np.arange(6.0).reshape(2, 3)))
np.savez("complex.npz", bad=np.array([1 + 2j, 3 - 1j]))
np.savez("bigendian.npz", bad=np.array([1.0, 2.0], dtype=">f8"))
write_zip("bad_magic.npz", [("bad.npy", b"PK this is not an npy array")])
# header says (4,) float64 = 32 bytes, data has 24
write_zip("short_data.npz", [("bad.npy", npy_bytes(np.arange(4.0))[:-8])])

# A 2-3-1 network (tanh, linear) for Mlp::from_npz: net_W1 (3,2), net_b1 (3,), net_W2 (1,3),
# net_b2 (1,). tests/dynamics/test_mlp.cpp checks forward([0.5, -1]) against the value numpy
# prints here.
W1 = np.array([[0.5, -1.0], [2.0, 0.25], [-0.75, 1.5]])
b1 = np.array([0.1, -0.2, 0.3])
W2 = np.array([[1.0, -2.0, 0.5]])
b2 = np.array([0.05])
np.savez("mlp_small.npz", net_W1=W1, net_b1=b1, net_W2=W2, net_b2=b2)
print("mlp_small forward([0.5, -1]) =", repr((W2 @ np.tanh(W1 @ np.array([0.5, -1.0]) + b1) + b2)[0]))
# Layers that do not chain: W2 is (1, 4) after a 3-output layer.
np.savez("mlp_bad_chain.npz", net_W1=W1, net_b1=b1, net_W2=np.ones((1, 4)), net_b2=b2)

# AutoRally-style keys with one wrong shape (dynamics_W2 is (16, 32) instead of (32, 32)),
# float32 zeros, deflated: AutoRallyNetwork::load must name the array and both shapes.
np.savez_compressed(
    "autorally_bad_shape.npz",
    dynamics_W1=np.zeros((32, 6), np.float32), dynamics_b1=np.zeros(32, np.float32),
    dynamics_W2=np.zeros((16, 32), np.float32), dynamics_b2=np.zeros(16, np.float32),
    dynamics_W3=np.zeros((4, 16), np.float32), dynamics_b3=np.zeros(4, np.float32))

# Non-finite values in well-formed files (tests/mppi/test_nonfinite_inputs.cpp): the loaders must
# refuse them, naming the file and the array.
# AutoRally network, right shapes, float32 zeros except dynamics_b2[5] = NaN.
b2 = np.zeros(32, np.float32)
b2[5] = np.nan
np.savez("autorally_nan.npz",
         dynamics_W1=np.zeros((32, 6), np.float32), dynamics_b1=np.zeros(32, np.float32),
         dynamics_W2=np.zeros((32, 32), np.float32), dynamics_b2=b2,
         dynamics_W3=np.zeros((4, 32), np.float32), dynamics_b3=np.zeros(4, np.float32))
# float64 1e300 in dynamics_W3[1, 2]: finite as a double, infinite as the float the model uses.
W3 = np.zeros((4, 32))
W3[1, 2] = 1e300
np.savez("autorally_overflow.npz",
         dynamics_W1=np.zeros((32, 6)), dynamics_b1=np.zeros(32),
         dynamics_W2=np.zeros((32, 32)), dynamics_b2=np.zeros(32),
         dynamics_W3=W3, dynamics_b3=np.zeros(4))
# Cost map (AutoRally layout): x in [0, 2] m, y in [0, 1] m, 2 pixels per metre -> 4 x 2 cells,
# channel0 row-major by y; cell (row 1, col 1) = index 5 is NaN, cell (row 0, col 3) = +inf in
# costmap_inf.npz.
c = np.arange(8, dtype=np.float32)
c[5] = np.nan
np.savez("costmap_nan.npz", xBounds=np.array([0.0, 2.0]), yBounds=np.array([0.0, 1.0]),
         pixelsPerMeter=np.array([2.0]), channel0=c)
c = np.arange(8, dtype=np.float32)
c[3] = np.inf
np.savez("costmap_inf.npz", xBounds=np.array([0.0, 2.0]), yBounds=np.array([0.0, 1.0]),
         pixelsPerMeter=np.array([2.0]), channel0=c)
