// Internal: independent, seed-determined random streams (one per purpose), so that e.g. changing
// points_per_frame does not change the IMU noise or the biases.
#pragma once

#include <cstdint>
#include <random>

namespace freeinit::sim::detail {

/// Purposes of the random streams.
enum class Stream : std::uint32_t {
  Biases = 1,
  Extrinsics = 2,
  Scene = 3,
  Imu = 4,
  Lidar = 5,
  // randomScenario(seed): one stream per aspect, so that changing one part of the distribution
  // leaves the draws of the others as they were.
  DrawPlatform = 16,
  DrawMotion = 17,
  DrawScene = 18,
  DrawMovers = 19,
  DrawSensors = 20,
  DrawCalibration = 21,
  // drawMisdeclaration(seed, ...): what an evaluation hands the estimator instead of the truth;
  // apart from every stream above, so that a seed's recording does not depend on it.
  DrawMisdeclaration = 22,
};

inline std::mt19937_64 randomStream(std::uint64_t seed, Stream purpose) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(purpose), 0x5eedu};
  return std::mt19937_64(seq);
}

}  // namespace freeinit::sim::detail
