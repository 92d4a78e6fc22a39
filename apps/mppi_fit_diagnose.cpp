// Placeholder: the issue-5 engineer replaces this file with the real `mppi-fit diagnose`.
#include <cstdio>

#include "mppi_fit_commands.hpp"

int mppi_fit_diagnose(int, char**) {
  std::fputs("mppi-fit diagnose: not built yet\n", stderr);
  return 2;
}
