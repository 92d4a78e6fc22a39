// The subcommands of mppi-fit; each parses its own arguments (argv[0] is the subcommand name)
// and returns the process exit status (0 ok, 1 failure, 2 usage error).
#pragma once

int mppi_fit_estimate(int argc, char** argv);  // apps/mppi_fit_estimate.cpp
int mppi_fit_convert(int argc, char** argv);   // apps/mppi_fit_convert.cpp
int mppi_fit_diagnose(int argc, char** argv);  // apps/mppi_fit_diagnose.cpp
int mppi_fit_protocol(int argc, char** argv);  // apps/mppi_fit_protocol.cpp
int mppi_fit_calibrate(int argc, char** argv); // apps/mppi_fit_calibrate.cpp
