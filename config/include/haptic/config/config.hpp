#pragma once

// Umbrella header: the typed configuration of the haptic runtime and its strict loaders.
// Every loader throws haptic::config::ConfigError naming file, line, key and expectation.

#include "haptic/config/common.hpp"  // IWYU pragma: export
#include "haptic/config/daemon.hpp"  // IWYU pragma: export
#include "haptic/config/device.hpp"  // IWYU pragma: export
#include "haptic/config/enums.hpp"   // IWYU pragma: export
#include "haptic/config/error.hpp"   // IWYU pragma: export
#include "haptic/config/scene.hpp"   // IWYU pragma: export
#include "haptic/config/sim.hpp"     // IWYU pragma: export
#include "haptic/config/types.hpp"   // IWYU pragma: export
