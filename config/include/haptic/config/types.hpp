#pragma once

#include <array>
#include <cstddef>
#include <numbers>

namespace haptic::config {

// Plain arrays rather than Eigen types: the config library is read by every process and
// should not impose a math library on them. Conversion is one Eigen::Map away.
using Vec2 = std::array<double, 2>;
using Vec3 = std::array<double, 3>;

struct Interval {
    double min;
    double max;

    friend bool operator==(const Interval&, const Interval&) = default;
};

// Rotations are written as roll-pitch-yaw in degrees and stored in radians. Convention:
// R = Rz(yaw) * Ry(pitch) * Rx(roll), i.e. extrinsic rotations about the parent's x, y, z.
struct Pose {
    Vec3 position_m{};
    Vec3 rpy_rad{};

    friend bool operator==(const Pose&, const Pose&) = default;
};

// A calibration transform T_a_b (pose of frame b in frame a), same conventions as Pose.
struct Transform {
    Vec3 translation_m{};
    Vec3 rpy_rad{};

    friend bool operator==(const Transform&, const Transform&) = default;
};

inline constexpr double kRadPerDeg = std::numbers::pi / 180.0;

[[nodiscard]] constexpr double degToRad(double degrees) noexcept {
    return degrees * kRadPerDeg;
}

template <std::size_t N>
[[nodiscard]] constexpr std::array<double, N> degToRad(
    const std::array<double, N>& degrees) noexcept {
    std::array<double, N> out{};
    for (std::size_t i = 0; i < N; ++i) {
        out[i] = degToRad(degrees[i]);
    }
    return out;
}

[[nodiscard]] constexpr Interval degToRad(const Interval& degrees) noexcept {
    return Interval{degToRad(degrees.min), degToRad(degrees.max)};
}

}  // namespace haptic::config
