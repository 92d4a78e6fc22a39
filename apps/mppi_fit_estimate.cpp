// mppi-fit estimate (in progress).
#include <cstdio>

#include "mppi_fit_commands.hpp"

int mppi_fit_estimate(int, char**) {
  std::fputs("mppi-fit estimate: not built yet\n", stderr);
  return 2;
}
