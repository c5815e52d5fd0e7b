#pragma once

#include <cstddef>

// Capacities of the fixed-size message twins. The IDL bounds in msgs/schema/idl/*.idl carry
// the same numbers; msgs/schema/src/conversions.cpp static_asserts that they agree.
namespace haptic::msgs {

inline constexpr std::size_t kIdCapacity = 32;  // 31 characters + NUL
inline constexpr std::size_t kShortTextCapacity = 96;
inline constexpr std::size_t kLongTextCapacity = 128;
inline constexpr std::size_t kModelNameCapacity = 64;

inline constexpr std::size_t kMaxJointDofs = 8;
inline constexpr std::size_t kMaxActuators = 4;
inline constexpr std::size_t kThimbleServos = 3;  // the 3-RRS platform
inline constexpr std::size_t kMaxConstraints = 16;
inline constexpr std::size_t kMaxContactJoints = 4;  // joints behind one contact (a finger's)
inline constexpr std::size_t kMaxContactSamples = 128;
inline constexpr std::size_t kMaxHandJointAngles = 32;
inline constexpr std::size_t kMaxStatusDevices = 4;
inline constexpr std::size_t kMaxStatusFaults = 8;
inline constexpr std::size_t kMaxTelemetrySamples = 32;

// The largest twin must fit the biggest RouDi mempool chunk in config/roudi.toml.
inline constexpr std::size_t kMaxShmPayloadBytes = 16384;

}  // namespace haptic::msgs
