// Internal: the preset definitions, shared by preset() and the default ScenarioConfig.
#pragma once

#include <freeinit/sim/scenario.h>

#include <string>

namespace freeinit::sim::detail {

/// Sets the motion, scene and calibration of preset `name` in c (not its name, seed, sensor rates
/// or noise). Throws std::invalid_argument on an unknown name.
void definePreset(const std::string& name, ScenarioConfig& c);

}  // namespace freeinit::sim::detail
