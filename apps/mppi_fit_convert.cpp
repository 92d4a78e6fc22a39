// mppi-fit convert (in progress).
#include <cstdio>

#include "mppi_fit_commands.hpp"

int mppi_fit_convert(int, char**) {
  std::fputs("mppi-fit convert: not built yet\n", stderr);
  return 2;
}
