#pragma once
// make_controller() lives in the core (mppi/make_controller.hpp); the Vulkan backend registers
// itself there when this library is linked. This header stays for existing includes.
#include "kernels/vulkan_backend.hpp"
#include "mppi/make_controller.hpp"
