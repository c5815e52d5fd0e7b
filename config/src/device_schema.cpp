#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>

#include "haptic/config/device.hpp"
#include "schema.hpp"

namespace haptic::config {
namespace detail {
namespace {

using spec::Real;

// Standard CAN nominal bit rates; anything else is almost certainly a typo.
// Matches msgs kMaxConstraints and kMaxContactSamples: the RT path has fixed capacities.
constexpr int kMaxConstraints = 16;
constexpr int kMaxPadSamples = 128;

std::string hexId(std::uint32_t id) {
    char buffer[16];
    std::snprintf(buffer, sizeof(buffer), "0x%03x", id);
    return buffer;
}

// Linux interface names: IFNAMSIZ - 1 characters, no '/', ':' or whitespace.
std::string readInterface(MapReader& can) {
    auto [name, field] = can.requiredWithField("interface", spec::Text{});
    const bool valid = name.size() <= 15 && std::none_of(name.begin(), name.end(), [](char c) {
                           return c == '/' || c == ':' || c == ' ' || c == '\t';
                       });
    if (!valid) {
        field.fail("a network interface name of 1 to 15 characters without '/', ':' or spaces");
    }
    return name;
}

CanConfig readCan(MapReader can) {
    CanConfig out;
    out.transport = can.optional("transport", CanTransport::kSocketCan, spec::Enum<CanTransport>{});
    // Each transport's own keys name its bus; the other's would be read and then do nothing.
    if (out.transport == CanTransport::kSocketCan) {
        out.interface = readInterface(can);
        out.fd = can.optional("fd", false, spec::Boolean{});
    } else {
        for (const char* key : {"interface", "fd"}) {
            if (const auto field = can.take(key)) {
                field->fail(
                    "can.transport: socketcan with this key (a UDP bus is named by "
                    "can.udp_port)",
                    "can.transport: udp");
            }
        }
    }

    // The bit rate is the interface's (ip link, or systemd-networkd's [CAN] BitRate=): hapticd
    // neither sets nor can check it, so a key here would only look like a setting.
    if (auto bitrate = can.take("bitrate")) {
        bitrate->failWith(
            "not a hapticd setting; the bit rate is the interface's (ip link set "
            "<interface> type can bitrate ..., or systemd-networkd's [CAN] BitRate=), remove "
            "the key");
    }

    // 11-bit standard ids; each must be distinct or frames of one kind would be parsed as
    // another.
    const auto id_spec = spec::Integer<std::uint32_t>::hexClosed(0, 0x7FF);
    const std::array<const char*, 4> names{"command_id", "state_id", "heartbeat_id", "fault_id"};
    std::array<std::uint32_t*, 4> targets{&out.command_id, &out.state_id, &out.heartbeat_id,
                                          &out.fault_id};
    for (std::size_t i = 0; i < names.size(); ++i) {
        auto [id, field] = can.requiredWithField(names[i], id_spec);
        for (std::size_t j = 0; j < i; ++j) {
            if (*targets[j] == id) {
                field.fail(
                    std::string("a CAN id different from can.") + names[j] + " (" + hexId(id) + ")",
                    hexId(id));
            }
        }
        *targets[i] = id;
    }
    out.heartbeat_timeout_ms =
        can.required("heartbeat_timeout_ms", spec::Integer<int>::closed(1, 1000));
    out.state_timeout_ms = can.required("state_timeout_ms", spec::Integer<int>::closed(1, 1000));
    // At least two 1 kHz command periods, so one lost frame never trips it; at most 100 ms,
    // because past that the device is no longer watching for its host.
    out.command_timeout_ms = can.required("command_timeout_ms", spec::Integer<int>::closed(2, 100));

    const auto udp_port = can.take("udp_port");
    const auto udp_slots = can.take("udp_slots");
    if (out.transport != CanTransport::kUdp) {
        for (const auto* field : {&udp_port, &udp_slots}) {
            if (field->has_value()) {
                (*field)->fail(
                    "can.transport: udp with this key (a SocketCAN bus is named by "
                    "can.interface)",
                    "can.transport: socketcan");
            }
        }
    } else {
        if (udp_slots) {
            out.udp_slots = udp_slots->as(spec::Integer<std::uint16_t>::closed(2, 32));
        }
        if (udp_port) {
            out.udp_port = udp_port->as(spec::Integer<std::uint16_t>::closed(1024, 65535));
            if (static_cast<int>(out.udp_port) + out.udp_slots - 1 > 65535) {
                udp_port->fail("a first port whose block of can.udp_slots (" +
                               std::to_string(out.udp_slots) + ") ports ends at or below 65535");
            }
        }
    }
    can.finish();
    return out;
}

struct Safety {
    SafetyLimits limits;
    std::optional<Field> max_force_field;      // for the check against the actuator
    std::optional<Field> max_stiffness_field;  // for the passivity margin
    std::optional<Field> max_velocity_field;   // for the check against the drive's speed
};

Safety readSafety(MapReader safety, DeviceType type) {
    SafetyLimits out;
    auto [max_force, max_force_field] =
        safety.requiredWithField("max_force_n", Real::positive(100.0));
    out.max_force_n = max_force;
    auto [max_velocity, max_velocity_field] =
        safety.requiredWithField("max_velocity_m_per_s", Real::positive(5.0));
    out.max_velocity_m_per_s = max_velocity;
    out.max_force_rate_n_per_s =
        safety.required("max_force_rate_n_per_s", Real::positive(100'000.0));
    if (type == DeviceType::kThimble) {
        // The plate is position-controlled: the stiffness the finger meets is its own pad's,
        // and a stale device is retracted at once rather than faded. Keys with no effect are
        // refused, not ignored.
        for (const char* key : {"max_stiffness_n_per_m", "fade_out_ms"}) {
            if (const auto field = safety.take(key)) {
                field->failWith(
                    std::string("not a thimble key: the exoskeleton's only (the "
                                "thimble's plate is position-controlled; its "
                                "limits are max_force_n, max_force_rate_n_per_s "
                                "and max_velocity_m_per_s)"));
            }
        }
        out.min_pad_stiffness_n_per_m =
            safety.required("min_pad_stiffness_n_per_m", Real::closed(1.0, 1e6));
        safety.finish();
        return Safety{out, std::move(max_force_field), std::nullopt, std::move(max_velocity_field)};
    }
    if (const auto field = safety.take("min_pad_stiffness_n_per_m")) {
        field->failWith("not an exoskeleton key: the thimble's only (the floor of its pad model)");
    }
    auto [max_stiffness, max_stiffness_field] =
        safety.requiredWithField("max_stiffness_n_per_m", Real::positive(20'000.0));
    out.max_stiffness_n_per_m = max_stiffness;
    out.fade_out_ms = safety.required("fade_out_ms", spec::Integer<int>::closed(1, 2000));
    safety.finish();
    return Safety{out, std::move(max_force_field), std::move(max_stiffness_field),
                  std::move(max_velocity_field)};
}

// --- exoskeleton ---

ActuatorConfig readActuator(MapReader map) {
    ActuatorConfig out;
    out.stroke_min_m = map.required("stroke_min_m", Real::closed(-0.2, 0.2));
    auto [stroke_max, stroke_max_field] =
        map.requiredWithField("stroke_max_m", Real::closed(-0.2, 0.2));
    if (!(stroke_max > out.stroke_min_m)) {
        stroke_max_field.fail("a number greater than actuator.stroke_min_m (" +
                              formatNumber(out.stroke_min_m) + ")");
    }
    out.stroke_max_m = stroke_max;
    out.max_force_n = map.required("max_force_n", Real::positive(500.0));
    out.max_speed_m_per_s = map.required("max_speed_m_per_s", Real::positive(5.0));
    out.lag_time_constant_s = map.required("lag_time_constant_s", Real::closed(0.0, 1.0));
    out.damping_n_s_per_m = map.required("damping_n_s_per_m", Real::closed(0.0, 10'000.0));
    out.force_tolerance_n =
        map.optional("force_tolerance_n", out.force_tolerance_n, Real::positive(100.0));
    map.finish();
    return out;
}

FingerConfig readFinger(MapReader map) {
    FingerConfig out;
    // Human phalanges are 5-80 mm; metres typed as millimetres fail here.
    out.phalanx_lengths_m =
        map.required("phalanx_lengths_m", spec::Reals<3>{Real::closed(0.005, 0.08)});
    const auto limits_deg = map.required(
        "joint_limits_deg", spec::Array<spec::Range, 3>{spec::Range{Real::closed(-90.0, 135.0)}});
    for (std::size_t i = 0; i < limits_deg.size(); ++i) {
        out.joint_limits_rad[i] = degToRad(limits_deg[i]);
    }
    map.finish();
    return out;
}

LinkageConfig readLinkage(MapReader map) {
    const auto point = spec::Reals<2>{Real::closed(-0.2, 0.2)};
    LinkageConfig out;
    out.actuator_base_m = map.required("actuator_base_m", point);
    out.proximal_attachment_m = map.required("proximal_attachment_m", point);
    out.rod_length_m = map.required("rod_length_m", Real::positive(0.3));
    out.distal_coupling_m_per_rad =
        map.required("distal_coupling_m_per_rad", spec::Reals<2>{Real::closed(-0.05, 0.05)});
    map.finish();
    return out;
}

ExoskeletonRenderingConfig readExoRendering(MapReader map, std::optional<int> control_rate_hz) {
    ExoskeletonRenderingConfig out;
    out.method = map.required("method", spec::Enum<RenderingMethod>{});
    out.max_constraints =
        map.optional("max_constraints", 8, spec::Integer<int>::closed(1, kMaxConstraints));
    const ExoskeletonRenderingConfig defaults;
    out.tracking_stiffness_nm_per_rad =
        map.optional("tracking_stiffness_nm_per_rad", defaults.tracking_stiffness_nm_per_rad,
                     Real::positive(100.0));
    out.user_stiffness_nm_per_rad = map.optional(
        "user_stiffness_nm_per_rad", defaults.user_stiffness_nm_per_rad, Real::positive(100.0));
    out.actuator_damping_n_s_per_m =
        map.optional("actuator_damping_n_s_per_m", defaults.actuator_damping_n_s_per_m,
                     Real::closed(0.0, 1000.0));
    out.passivity_port_mass_kg = map.optional(
        "passivity_port_mass_kg", defaults.passivity_port_mass_kg, Real::positive(100.0));
    if (std::optional<MapReader> estimate = map.optionalMap("user_stiffness_estimate")) {
        UserStiffnessEstimateConfig& out_estimate = out.user_stiffness_estimate;
        out_estimate.enabled = estimate->required("enabled", spec::Boolean{});
        // Below 10 um the finger's answer sinks into the encoders' resolution (about 1 um
        // along the actuator) and no estimate would ever come.
        out_estimate.probe_amplitude_m = estimate->optional(
            "probe_amplitude_m", out_estimate.probe_amplitude_m, Real::closed(10e-6, 1e-3));
        if (std::optional<Field> frequency = estimate->take("probe_frequency_hz")) {
            out_estimate.probe_frequency_hz = Real::closed(1.0, 10.0).parse(*frequency);
            // The upper tone (twice this) at most a twentieth of the loop rate: the estimator's
            // phase steps stay fine enough to read both tones.
            if (control_rate_hz &&
                2.0 * out_estimate.probe_frequency_hz > *control_rate_hz / 20.0) {
                frequency->fail("at most loop.rate_hz / 40 (" +
                                formatNumber(*control_rate_hz / 40.0) + ")");
            }
        }
        if (std::optional<Field> probe_time = estimate->take("probe_time_s")) {
            out_estimate.probe_time_s = Real::closed(0.1, 60.0).parse(*probe_time);
            // The estimator's window is two periods of the lower tone.
            if (out_estimate.probe_time_s * out_estimate.probe_frequency_hz < 2.0) {
                probe_time->fail("at least two periods of probe_frequency_hz (" +
                                 formatNumber(2.0 / out_estimate.probe_frequency_hz) + " s)");
            }
        }
        estimate->finish();
    }
    map.finish();
    return out;
}

ExoskeletonConfig readExoskeleton(MapReader& root, const Safety& safety,
                                  std::optional<int> control_rate_hz) {
    ExoskeletonConfig out;
    out.actuator = readActuator(root.requiredMap("actuator"));
    out.finger = readFinger(root.requiredMap("finger"));
    out.linkage = readLinkage(root.requiredMap("linkage"));
    out.rendering = readExoRendering(root.requiredMap("rendering"), control_rate_hz);
    // The safety limit is a promise the actuator must be able to keep.
    if (safety.limits.max_force_n > out.actuator.max_force_n) {
        safety.max_force_field->fail("a number no greater than actuator.max_force_n (" +
                                     formatNumber(out.actuator.max_force_n) + ")");
    }
    // The velocity fade takes away a force that drives the rod along its motion; at and above
    // the drive's no-load speed the drive itself delivers none, so a limit there does nothing.
    if (!(safety.limits.max_velocity_m_per_s < out.actuator.max_speed_m_per_s)) {
        safety.max_velocity_field->fail("a number below actuator.max_speed_m_per_s (" +
                                        formatNumber(out.actuator.max_speed_m_per_s) +
                                        ", the drive's no-load speed: a limit there does nothing)");
    }
    // Colgate and Schenkel's sampled-data passivity along the actuator (docs/algorithms.md
    // §1.5, §6.9): b > K T / 2 + |b_v|, with K the stiffness the rendering is clamped to, b the
    // actuator's own damping and b_v the rendered damping.
    if (control_rate_hz) {
        const double period_s = 1.0 / static_cast<double>(*control_rate_hz);
        const double needed = 0.5 * safety.limits.max_stiffness_n_per_m * period_s +
                              out.rendering.actuator_damping_n_s_per_m;
        if (!(out.actuator.damping_n_s_per_m > needed)) {
            safety.max_stiffness_field->failWith(
                "not passive at loop.rate_hz " + std::to_string(*control_rate_hz) +
                ": needs actuator.damping_n_s_per_m (" +
                formatNumber(out.actuator.damping_n_s_per_m) +
                ") > max_stiffness_n_per_m * T / 2 + rendering.actuator_damping_n_s_per_m (" +
                formatNumber(needed) + "); lower the stiffness or raise the loop rate");
        }
    }
    return out;
}

// --- thimble ---

ThimbleGeometry readGeometry(MapReader map) {
    // A fingertip device: every dimension is millimetres to a few centimetres.
    const Real length = Real::positive(0.1);
    ThimbleGeometry out;
    out.base_radius_m = map.required("base_radius_m", length);
    out.platform_radius_m = map.required("platform_radius_m", length);
    out.crank_length_m = map.required("crank_length_m", length);
    out.link_length_m = map.required("link_length_m", length);
    auto [angles_deg, angles_field] =
        map.requiredWithField("leg_angles_deg", spec::Reals<3>{Real::closed(-360.0, 360.0)});
    // Coincident legs make the platform singular; real designs are ~120 degrees apart.
    for (std::size_t i = 0; i < 3; ++i) {
        for (std::size_t j = i + 1; j < 3; ++j) {
            const double gap = std::fabs(std::remainder(angles_deg[i] - angles_deg[j], 360.0));
            if (gap < 30.0) {
                angles_field.fail("three leg angles at least 30 degrees apart",
                                  "[" + formatNumber(angles_deg[0]) + ", " +
                                      formatNumber(angles_deg[1]) + ", " +
                                      formatNumber(angles_deg[2]) + "]");
            }
        }
    }
    out.leg_angles_rad = degToRad(angles_deg);
    map.finish();
    return out;
}

ServoConfig readServos(MapReader map) {
    ServoConfig out;
    const double min_deg = map.required("min_deg", Real::closed(-180.0, 180.0));
    auto [max_deg, max_field] = map.requiredWithField("max_deg", Real::closed(-180.0, 180.0));
    if (!(max_deg > min_deg)) {
        max_field.fail("a number greater than servos.min_deg (" + formatNumber(min_deg) + ")");
    }
    out.min_rad = degToRad(min_deg);
    out.max_rad = degToRad(max_deg);
    out.max_rate_rad_per_s = degToRad(map.required("max_rate_deg_per_s", Real::positive(2000.0)));
    out.lag_time_constant_s = map.required("lag_time_constant_s", Real::closed(0.0, 1.0));
    out.angle_tolerance_rad =
        degToRad(map.optional("angle_tolerance_deg", 5.0, Real::positive(90.0)));
    map.finish();
    return out;
}

FingerCalibration readCalibration(MapReader map) {
    FingerCalibration out;
    out.contact_height_m = map.required("contact_height_m", Real::closed(-0.1, 0.1));
    out.max_indentation_m = map.required("max_indentation_m", Real::positive(0.01));
    out.T_finger_device = readTransform(map.requiredMap("T_finger_device"));
    map.finish();
    return out;
}

OptimiserConfig readOptimiser(MapReader map) {
    OptimiserConfig out;
    out.max_iterations = map.required("max_iterations", spec::Integer<int>::closed(1, 1000));
    out.pad_samples =
        map.optional("pad_samples", 64, spec::Integer<int>::closed(1, kMaxPadSamples));
    out.pad_stiffening_depth_m =
        map.optional("pad_stiffening_depth_m", out.pad_stiffening_depth_m, Real::positive(0.1));
    map.finish();
    return out;
}

ThimbleConfig readThimble(MapReader& root) {
    ThimbleConfig out;
    out.geometry = readGeometry(root.requiredMap("geometry"));
    out.servos = readServos(root.requiredMap("servos"));
    out.plate_radius_m = root.required("plate_radius_m", Real::positive(0.05));
    // The cable-driven predecessor reached 30 degrees; beyond 60 the legs fold.
    out.max_tilt_rad = degToRad(root.required("max_tilt_deg", Real::closed(0.0, 60.0)));
    out.spherical_joint_max_rad =
        degToRad(root.optional("spherical_joint_max_deg", 70.0, Real::closed(10.0, 90.0)));
    out.finger_calibration = readCalibration(root.requiredMap("finger_calibration"));
    out.optimiser = readOptimiser(root.requiredMap("optimiser"));
    return out;
}

}  // namespace

DeviceConfig readDevice(MapReader root, const std::filesystem::path& source,
                        std::optional<int> control_rate_hz) {
    DeviceConfig out;
    out.source = source;
    out.name = root.required("name", spec::Identifier{});
    const DeviceType type = root.required("type", spec::Enum<DeviceType>{});
    out.can = readCan(root.requiredMap("can"));
    const Safety safety = readSafety(root.requiredMap("safety"), type);
    out.safety = safety.limits;
    switch (type) {
        case DeviceType::kExoskeleton:
            out.params = readExoskeleton(root, safety, control_rate_hz);
            break;
        case DeviceType::kThimble:
            out.params = readThimble(root);
            break;
    }
    root.finish();
    return out;
}

}  // namespace detail

DeviceConfig loadDeviceConfig(const std::filesystem::path& path) {
    return detail::readDevice(MapReader::openFile(path), path);
}

}  // namespace haptic::config
