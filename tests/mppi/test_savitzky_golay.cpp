#include <catch2/catch.hpp>
#include <vector>

#include "mppi/savitzky_golay.hpp"

TEST_CASE("Savitzky-Golay: textbook coefficients and polynomial preservation", "[core][smoothing]") {
  const mppi::SavitzkyGolay sg(20, 5, 2);
  // Interior point, window 5, quadratic: (-3, 12, 17, 12, -3) / 35 (Savitzky & Golay 1964).
  const float expected[5] = {-3 / 35.f, 12 / 35.f, 17 / 35.f, 12 / 35.f, -3 / 35.f};
  for (int r = 0; r < 5; ++r) CHECK(sg.weights(10)[r] == Approx(expected[r]).margin(1e-6));
  CHECK(sg.start(10) == 8);
  CHECK(sg.start(0) == 0);   // shifted window at the ends
  CHECK(sg.start(19) == 15);
  // A quadratic passes unchanged everywhere, ends included; noise is reduced.
  std::vector<float> in(20), out(20);
  for (int i = 0; i < 20; ++i) in[i] = 0.5f - 0.1f * i + 0.02f * i * i;
  sg.apply(in.data(), out.data(), 1);
  for (int i = 0; i < 20; ++i) CHECK(out[i] == Approx(in[i]).margin(2e-5));
  // Interleaved channels: stride 2 smooths each channel on its own.
  std::vector<float> two(40), two_out(40);
  for (int i = 0; i < 20; ++i) { two[2 * i] = in[i]; two[2 * i + 1] = (i % 2) ? 1.f : -1.f; }
  sg.apply(two.data(), two_out.data(), 2);
  sg.apply(two.data() + 1, two_out.data() + 1, 2);
  for (int i = 0; i < 20; ++i) CHECK(two_out[2 * i] == Approx(in[i]).margin(2e-5));
  CHECK(std::abs(two_out[21]) < 0.5f);  // alternating +-1 is mostly removed
  CHECK_THROWS_AS(mppi::SavitzkyGolay(20, 4, 2), mppi::Error);
}
