#pragma once

// One YAML file per physical device (config/devices/*.yaml). The common part (name, CAN,
// safety limits) is the same for every device; the rest depends on `type`.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <variant>

#include "haptic/config/enums.hpp"
#include "haptic/config/types.hpp"

namespace haptic::config {

enum class DeviceType { kExoskeleton, kThimble };

template <>
struct EnumTraits<DeviceType> {
    static constexpr std::array<EnumEntry<DeviceType>, 2> kEntries{{
        {"exoskeleton", DeviceType::kExoskeleton},
        {"thimble", DeviceType::kThimble},
    }};
};

// Kinesthetic rendering methods (docs/algorithms.md §5.1-5.5, §6.5). The names are also what
// haptic/command's set-method argument carries.
enum class RenderingMethod {
    kStandard,
    kNaive,
    kNullspace,
    kSubspace,
    kLinearizedSubspace,
    kAnisotropic
};

template <>
struct EnumTraits<RenderingMethod> {
    static constexpr std::array<EnumEntry<RenderingMethod>, 6> kEntries{{
        {"standard", RenderingMethod::kStandard},
        {"naive", RenderingMethod::kNaive},
        {"nullspace", RenderingMethod::kNullspace},
        {"subspace", RenderingMethod::kSubspace},
        {"linearized_subspace", RenderingMethod::kLinearizedSubspace},
        {"anisotropic", RenderingMethod::kAnisotropic},
    }};
};

// Which bus hapticd opens for the device: the SocketCAN interface (real hardware, vcan) or
// the UDP CAN bus on loopback that hapticemu speaks where the kernel has no SocketCAN.
enum class CanTransport { kSocketCan, kUdp };

template <>
struct EnumTraits<CanTransport> {
    static constexpr std::array<EnumEntry<CanTransport>, 2> kEntries{{
        {"socketcan", CanTransport::kSocketCan},
        {"udp", CanTransport::kUdp},
    }};
};

// YAML: can: {...}. Ids are 11-bit standard ids, pairwise distinct within a device; the
// daemon and sim loaders also reject two devices on one bus (bus()) sharing an id.
struct CanConfig {
    // Optional key transport (default socketcan). With socketcan: interface (required) and fd;
    // with udp: udp_port and udp_slots (defaults 47000 and 8; hapticemu -d <file> joins the
    // same block). Each transport refuses the other's keys.
    std::string interface;  // SocketCAN interface name (1-15 chars), e.g. "can0"; empty on UDP
    CanTransport transport{CanTransport::kSocketCan};
    std::uint16_t udp_port{47000};  // first port of the UDP bus's port block
    std::uint16_t udp_slots{8};     // parties on the UDP bus (2..32)
    bool fd{false};                 // CAN FD frames (needs an FD-capable interface, MTU 72)
    std::uint32_t command_id{0};    // host -> device setpoints
    std::uint32_t state_id{0};      // device -> host sensed state
    std::uint32_t heartbeat_id{0};
    std::uint32_t fault_id{0};
    int heartbeat_timeout_ms{0};  // no heartbeat for this long: device goes to safe state
    int state_timeout_ms{0};      // no state frame for this long: device goes to safe state
    // The device's own watchdog (written into the protocol, docs/drivers.md): no valid command
    // for this long and the device goes to its safe state by itself (exoskeleton disabled at
    // 0 N, thimble retracted) and reports fault 4, whatever happened to the host.
    int command_timeout_ms{0};

    // The bus the device is on, as hapticd opens it: one per SocketCAN interface, one per UDP
    // port block. Devices with the same bus share it and must not share a CAN id.
    [[nodiscard]] std::string bus() const {
        return transport == CanTransport::kUdp ? "UDP port " + std::to_string(udp_port)
                                               : "SocketCAN " + interface;
    }
};

// YAML: safety: {...}. Hard limits enforced by hapticd after rendering, whatever the method.
struct SafetyLimits {
    double max_force_n{0.0};  // exo: at the fingertip; thimble: on the pad, by its pad model
    // exo: actuator rod speed above which a force driving it fades; thimble: the plate's
    // approach speed towards the finger
    double max_velocity_m_per_s{0.0};
    // exo: slew limit on the commanded force; thimble: how fast the pad force may rise
    double max_force_rate_n_per_s{0.0};
    // Exoskeleton only (0 for a thimble, whose file may not carry them):
    double max_stiffness_n_per_m{0.0};  // the coupling along the actuator is clamped to it
    int fade_out_ms{0};                 // ramp to zero force on a stale device state
    // Thimble only (0 for an exoskeleton): the pad model the force limits judge with (the sim's
    // sample weights) is never taken softer than this in total (the sum of the weights, N/m):
    // a sim that sent weights too small by a unit (mm^2 for m^2) would switch the limits off.
    double min_pad_stiffness_n_per_m{0.0};
};

// --- exoskeleton (docs/algorithms.md §5.8)
// ---------------------------------------------------------

// YAML: actuator: {...}. The single linear actuator.
struct ActuatorConfig {
    double stroke_min_m{0.0};
    double stroke_max_m{0.0};
    double max_force_n{0.0};
    double max_speed_m_per_s{0.0};
    double lag_time_constant_s{0.0};  // first-order force response, used by the emulator
    // Viscous damping of the unpowered rod (motor and screw), what keeps a sampled spring
    // passive (the margin check on safety.max_stiffness_n_per_m); the emulator applies it.
    double damping_n_s_per_m{0.0};
    // How far the force the device measures may stray from the commanded force, seen through
    // the actuator's lag, before hapticd calls the feedback implausible (plus 20 % of it).
    double force_tolerance_n{1.0};
};

// YAML: finger: {phalanx_lengths_m: [l1, l2, l3], joint_limits_deg: [[min, max] x 3]}.
// Planar 3R chain MCP, PIP, DIP; flexion positive. Frame F: origin on the MCP axis, x along
// the straight finger towards the tip, y towards the palm (so dorsal points have y < 0).
struct FingerConfig {
    Vec3 phalanx_lengths_m{};
    std::array<Interval, 3> joint_limits_rad{};
};

// YAML: linkage: {...}. Assumed closure model ell = sigma(q) for the dorsal linkage, used
// until a lab replaces it with its CAD values or a fitted table (docs/algorithms.md §5.8):
//
//   sigma(q) = |R(theta1) * proximal_attachment_m - actuator_base_m| - rod_length_m
//              + distal_coupling_m_per_rad[0] * theta2 + distal_coupling_m_per_rad[1] * theta3
//
// i.e. the actuator spans from a pivot on the back of the hand to a pivot on the proximal
// phalanx link, and the passive links to the middle and distal phalanges add stroke in
// proportion to PIP and DIP flexion.
struct LinkageConfig {
    Vec2 actuator_base_m{};        // rear pivot of the actuator, in frame F
    Vec2 proximal_attachment_m{};  // rod-end pivot, in the proximal phalanx frame
    double rod_length_m{0.0};      // pivot-to-pivot length at zero stroke
    Vec2 distal_coupling_m_per_rad{};
};

// YAML: rendering.user_stiffness_estimate: {enabled, probe_amplitude_m, probe_frequency_hz,
// probe_time_s}.
// The online estimate of k_u (docs/kinesthetic.md, "User stiffness"): while in contact the
// proxy is moved along the actuator by two sines of probe_amplitude_m each, at
// probe_frequency_hz and twice it, for the first probe_time_s of each contact (0: all of it);
// the finger's answer gives k_u (kinesthetic::
// UserStiffnessEstimator), and anisotropic's closed-form rho* follows it (rate-limited, and
// booked with the passivity controller like a moving wall, as is the probe itself). The user
// feels the probe as a ripple of k_u / |B|^2 times the finger's excursion: 0.2-0.5 N per tone
// at the shipped values on config/user.yaml's finger (docs/kinesthetic.md).
struct UserStiffnessEstimateConfig {
    bool enabled{false};
    double probe_amplitude_m{25e-6};
    double probe_frequency_hz{5.0};
    double probe_time_s{1.5};
};

// YAML: rendering: {method, max_constraints, ...}
struct ExoskeletonRenderingConfig {
    RenderingMethod method{RenderingMethod::kLinearizedSubspace};
    int max_constraints{8};  // linearised constraints used per tick (<= msgs kMaxConstraints)
    // The coupling (docs/kinesthetic.md): k_a pulls the finger towards the proxy in joint
    // space, k_u is the user's stiffness that the closed-form rho* assumes, b_v damps the
    // actuator while in contact.
    double tracking_stiffness_nm_per_rad{2.0};
    double user_stiffness_nm_per_rad{0.6};
    double actuator_damping_n_s_per_m{0.5};
    // A lower bound on the mass the actuator moves with a finger in the device (reflected to
    // the stroke): the passivity controller's worst case for how far its force carries it.
    double passivity_port_mass_kg{0.1};
    UserStiffnessEstimateConfig user_stiffness_estimate;
};

struct ExoskeletonConfig {
    ActuatorConfig actuator;
    FingerConfig finger;
    LinkageConfig linkage;
    ExoskeletonRenderingConfig rendering;
};

// --- thimble (docs/algorithms.md §3.6)
// -------------------------------------------------------------

// YAML: geometry: {...}. 3-RRS platform; base frame origin at the static body centre, z
// from nail towards pad.
struct ThimbleGeometry {
    double base_radius_m{0.0};      // r_b, servo-axis circle
    double platform_radius_m{0.0};  // r_p, spherical-joint circle on the platform
    double crank_length_m{0.0};     // l_1, servo link
    double link_length_m{0.0};      // l_2, distal link
    Vec3 leg_angles_rad{};          // gamma_i, angular placement of each leg
};

// YAML: servos: {min_deg, max_deg, max_rate_deg_per_s, lag_time_constant_s}
struct ServoConfig {
    double min_rad{0.0};
    double max_rad{0.0};
    double max_rate_rad_per_s{0.0};
    double lag_time_constant_s{0.0};  // first-order position response
    // A measured angle may differ from the one this response predicts for the commanded
    // targets by this much for up to can.heartbeat_timeout_ms before hapticd latches 105.
    double angle_tolerance_rad{0.0872664626};  // 5 degrees
};

// YAML: finger_calibration: {...}. Per user: where the pad is and how far it may be pressed.
struct FingerCalibration {
    double contact_height_m{0.0};   // plate height where the undeformed pad is first touched
    double max_indentation_m{0.0};  // the plate never goes below contact_height - this
    Transform T_finger_device;      // device base frame in the finger frame
};

// YAML: optimiser: {max_iterations, pad_samples, pad_stiffening_depth_m}. Bounds fix the
// worst-case tick cost.
struct OptimiserConfig {
    int max_iterations{0};
    int pad_samples{0};  // <= msgs kMaxContactSamples
    // s of the pad law p(delta) = p0 (exp(delta / s) - 1) the optimiser matches forces with;
    // the shipped value is fitted to the soft-hand FEM fingertip (tactile_fem_error_analysis).
    double pad_stiffening_depth_m{0.001};
};

struct ThimbleConfig {
    ThimbleGeometry geometry;
    ServoConfig servos;
    double plate_radius_m{0.0};  // r_d
    double max_tilt_rad{0.0};
    // Largest angle between a distal link and the plate normal that the spherical joints
    // allow (optional key spherical_joint_max_deg, default 70).
    double spherical_joint_max_rad{degToRad(70.0)};
    FingerCalibration finger_calibration;
    OptimiserConfig optimiser;
};

// -------------------------------------------------------------------------------------------

struct DeviceConfig {
    std::filesystem::path source;  // the file it was loaded from
    std::string name;              // [a-z0-9_]{1,31}, unique among the devices in use
    CanConfig can;
    SafetyLimits safety;
    std::variant<ExoskeletonConfig, ThimbleConfig> params;

    [[nodiscard]] DeviceType type() const noexcept {
        return params.index() == 0 ? DeviceType::kExoskeleton : DeviceType::kThimble;
    }
    [[nodiscard]] bool isExoskeleton() const noexcept { return params.index() == 0; }
    [[nodiscard]] bool isThimble() const noexcept { return params.index() == 1; }
    // Throw std::bad_variant_access on the wrong type.
    [[nodiscard]] const ExoskeletonConfig& exoskeleton() const {
        return std::get<ExoskeletonConfig>(params);
    }
    [[nodiscard]] const ThimbleConfig& thimble() const { return std::get<ThimbleConfig>(params); }
};

// Loads and validates one device file. Throws ConfigError.
[[nodiscard]] DeviceConfig loadDeviceConfig(const std::filesystem::path& path);

}  // namespace haptic::config
