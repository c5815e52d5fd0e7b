#include "haptic/msgs/conversions.hpp"

#include <cstdio>
#include <type_traits>

namespace haptic::msgs {
namespace {

// ---- compile-time agreement between the IDL bounds and the twin capacities ------------

template <typename Accessor>
using Member = std::remove_cvref_t<Accessor>;

template <typename T>
constexpr std::size_t kArraySize = std::tuple_size_v<T>;

static_assert(kArraySize<Member<decltype(idl::SimLinkStatus{}.rejected_by_reason())>> ==
              kSimInputRejectionReasons);
static_assert(kArraySize<Member<decltype(idl::ConstraintSet{}.q_sim_rad())>> == kMaxJointDofs);
static_assert(kArraySize<Member<decltype(idl::LinearConstraint{}.a())>> == kMaxJointDofs);
static_assert(kArraySize<Member<decltype(idl::ContactKinematics{}.q_ref_rad())>> ==
              kMaxContactJoints);
static_assert(kArraySize<Member<decltype(idl::ContactKinematics{}.axis())>> ==
              3 * kMaxContactJoints);
static_assert(kArraySize<Member<decltype(idl::ContactKinematics{}.lever_m())>> ==
              3 * kMaxContactJoints);
static_assert(kArraySize<Member<decltype(idl::ContactKinematics{}.normal())>> == 3);
static_assert(kArraySize<Member<decltype(idl::DeviceState{}.joint_position_rad())>> ==
              kMaxJointDofs);
static_assert(kArraySize<Member<decltype(idl::DeviceState{}.actuator_force())>> == kMaxActuators);
static_assert(kArraySize<Member<decltype(idl::ExoskeletonTelemetry{}.joint_position_rad())>> ==
              kMaxJointDofs);
static_assert(kArraySize<Member<decltype(idl::ExoskeletonTelemetry{}.proxy_position_rad())>> ==
              kMaxJointDofs);
static_assert(kArraySize<Member<decltype(idl::ConstraintSet{}.reference_torque_nm())>> ==
              kMaxJointDofs);
static_assert(kArraySize<Member<decltype(idl::ExoskeletonTelemetry{}.reference_torque_nm())>> ==
              kMaxJointDofs);
static_assert(kArraySize<Member<decltype(idl::ExoskeletonTelemetry{}.ghost_torque_nm())>> ==
              kMaxJointDofs);
static_assert(kArraySize<Member<decltype(idl::ThimbleTelemetry{}.servo_angle_cmd_rad())>> ==
              kThimbleServos);
static_assert(kArraySize<Member<decltype(idl::ThimbleTelemetry{}.servo_angle_rad())>> ==
              kThimbleServos);
static_assert(Member<decltype(idl::MessageHeader{}.source_id())>::max_size == kIdCapacity - 1);
static_assert(Member<decltype(idl::Fault{}.message())>::max_size == kShortTextCapacity - 1);
static_assert(Member<decltype(idl::HapticCommandReply{}.message())>::max_size ==
              kLongTextCapacity - 1);
static_assert(Member<decltype(idl::SimStatus{}.model())>::max_size == kModelNameCapacity - 1);
static_assert(Member<decltype(idl::SimStatus{}.last_rejection())>::max_size ==
              kShortTextCapacity - 1);
// Sequence bounds are not visible to the compiler; tests/msgs checks them by serialising
// a sample filled to capacity (must fit) and one past it (must not).

// ---- helpers ----------------------------------------------------------------------------

template <std::size_t N, std::size_t M>
void copyString(const FixedString<N>& in, eprosima::fastrtps::fixed_string<M>& out) {
    static_assert(M == N - 1);
    const auto text = in.view();
    out.assign(text.data(), text.size());
}

template <std::size_t N, std::size_t M>
void copyString(const eprosima::fastrtps::fixed_string<M>& in, FixedString<N>& out) {
    static_assert(M == N - 1);
    out.assign(std::string_view(in.c_str(), in.size()));
}

template <typename TwinEnum, typename IdlEnum>
bool convertEnum(IdlEnum in, TwinEnum last, TwinEnum& out, const char* field,
                 ConversionResult& result) {
    const auto raw = static_cast<std::uint32_t>(in);
    if (raw > static_cast<std::uint32_t>(last)) {
        result.error = std::string(field) + ": enum value " + std::to_string(raw) +
                       " is outside 0.." + std::to_string(static_cast<std::uint32_t>(last));
        return false;
    }
    out = static_cast<TwinEnum>(raw);
    return true;
}

template <typename T, std::size_t N>
bool fitsCapacity(std::size_t size, const BoundedArray<T, N>&, const char* field,
                  ConversionResult& result) {
    if (size > N) {
        result.error = std::string(field) + ": " + std::to_string(size) +
                       " entries exceed the capacity of " + std::to_string(N);
        return false;
    }
    return true;
}

template <typename IdlEnum, typename TwinEnum>
IdlEnum toIdlEnum(TwinEnum value) {
    return static_cast<IdlEnum>(static_cast<std::uint32_t>(value));
}

// Enumerator values must match one for one, or a cast silently changes meaning.
static_assert(static_cast<std::uint32_t>(idl::DAEMON_ESTOP) ==
              static_cast<std::uint32_t>(DaemonState::kEstop));
static_assert(static_cast<std::uint32_t>(idl::DAEMON_RENDERING) ==
              static_cast<std::uint32_t>(DaemonState::kRendering));
static_assert(static_cast<std::uint32_t>(idl::DEVICE_THIMBLE) ==
              static_cast<std::uint32_t>(DeviceKind::kThimble));
static_assert(static_cast<std::uint32_t>(idl::DEVICE_FAULT) ==
              static_cast<std::uint32_t>(DeviceRunState::kFault));
static_assert(static_cast<std::uint32_t>(idl::DEVICE_SAFE) ==
              static_cast<std::uint32_t>(DeviceRunState::kSafe));
static_assert(static_cast<std::uint32_t>(idl::BUS_OFF) ==
              static_cast<std::uint32_t>(BusState::kBusOff));
static_assert(static_cast<std::uint32_t>(idl::BUS_ERROR_PASSIVE) ==
              static_cast<std::uint32_t>(BusState::kErrorPassive));
static_assert(static_cast<std::uint32_t>(idl::TRANSPORT_DDS) ==
              static_cast<std::uint32_t>(SimTransport::kDds));
static_assert(static_cast<std::uint32_t>(idl::COMMAND_CLEAR_FAULT) ==
              static_cast<std::uint32_t>(CommandKind::kClearFault));
static_assert(static_cast<std::uint32_t>(idl::COMMAND_SET_METHOD) ==
              static_cast<std::uint32_t>(CommandKind::kSetMethod));

idl::MessageHeader toIdl(const MessageHeader& in) {
    idl::MessageHeader out;
    out.schema(in.schema);
    out.seq(in.seq);
    out.stamp_ns(in.stamp_ns);
    copyString(in.source_id, out.source_id());
    return out;
}

std::string hex32(std::uint32_t value) {
    char text[11];
    std::snprintf(text, sizeof(text), "0x%08x", value);
    return text;
}

// Every message's first step: the header, whatever its schema (a reader may count a refusal
// by its source), then the schema checked: read in another release's layout, the rest of the
// message means something else (a field added, moved or resized).
bool fromIdl(const idl::MessageHeader& in, MessageHeader& out, const char* message,
             ConversionResult& result) {
    out.schema = in.schema();
    out.seq = in.seq();
    out.stamp_ns = in.stamp_ns();
    copyString(in.source_id(), out.source_id);
    if (in.schema() == kSchema) {
        return true;
    }
    result.error = std::string(message) + ".header.schema: " + hex32(in.schema()) +
                   ", this build reads " + hex32(kSchema) +
                   " (the sender is from another release; hapticd, handsim, hapticemu and "
                   "hapticctl must come from one)";
    return false;
}

idl::TrackingOrigin toIdl(const TrackingOrigin& in) {
    idl::TrackingOrigin out;
    out.sampled_ns(in.sampled_ns);
    out.received_ns(in.received_ns);
    return out;
}

TrackingOrigin fromIdl(const idl::TrackingOrigin& in) {
    return TrackingOrigin{in.sampled_ns(), in.received_ns()};
}

idl::Percentiles toIdl(const Percentiles& in) {
    idl::Percentiles out;
    out.p50(in.p50);
    out.p99(in.p99);
    out.max(in.max);
    return out;
}

void fromIdl(const idl::Percentiles& in, Percentiles& out) {
    out.p50 = in.p50();
    out.p99 = in.p99();
    out.max = in.max();
}

}  // namespace

// ---- ConstraintSet ----------------------------------------------------------------------

idl::ConstraintSet toIdl(const ConstraintSet& in) {
    idl::ConstraintSet out;
    out.header(toIdl(in.header));
    out.dof(in.dof);
    out.q_sim_rad(in.q_sim_rad);
    out.constraints().reserve(in.constraints.size());
    for (const auto& c : in.constraints) {
        idl::LinearConstraint item;
        item.a(c.a);
        item.b(c.b);
        idl::ContactKinematics contact;
        contact.joints(c.contact.joints);
        contact.gap_m(c.contact.gap_m);
        contact.normal(c.contact.normal);
        contact.q_ref_rad(c.contact.q_ref_rad);
        for (std::size_t j = 0; j < kMaxContactJoints; ++j) {
            for (std::size_t k = 0; k < 3; ++k) {
                contact.axis()[3 * j + k] = c.contact.axis[j][k];
                contact.lever_m()[3 * j + k] = c.contact.lever_m[j][k];
            }
        }
        item.contact(contact);
        out.constraints().push_back(item);
    }
    out.reference_torque_nm(in.reference_torque_nm);
    out.tracking(toIdl(in.tracking));
    return out;
}

ConversionResult fromIdl(const idl::ConstraintSet& in, ConstraintSet& out) {
    ConversionResult result;
    if (!fromIdl(in.header(), out.header, "ConstraintSet", result)) {
        return result;
    }
    if (!fitsCapacity(in.constraints().size(), out.constraints, "ConstraintSet.constraints",
                      result)) {
        return result;
    }
    out.dof = in.dof();
    out.q_sim_rad = in.q_sim_rad();
    out.constraints.clear();
    for (const auto& c : in.constraints()) {
        LinearConstraint row{c.a(), c.b(), {}};
        const idl::ContactKinematics& contact = c.contact();
        row.contact.joints = contact.joints();
        row.contact.gap_m = contact.gap_m();
        row.contact.normal = contact.normal();
        row.contact.q_ref_rad = contact.q_ref_rad();
        for (std::size_t j = 0; j < kMaxContactJoints; ++j) {
            for (std::size_t k = 0; k < 3; ++k) {
                row.contact.axis[j][k] = contact.axis()[3 * j + k];
                row.contact.lever_m[j][k] = contact.lever_m()[3 * j + k];
            }
        }
        out.constraints.push_back(row);
    }
    out.reference_torque_nm = in.reference_torque_nm();
    out.tracking = fromIdl(in.tracking());
    return result;
}

// ---- ContactSurface ---------------------------------------------------------------------

idl::ContactSurface toIdl(const ContactSurface& in) {
    idl::ContactSurface out;
    out.header(toIdl(in.header));
    out.samples().reserve(in.samples.size());
    for (const auto& s : in.samples) {
        idl::ContactSample item;
        item.p_device_m(s.p_device_m);
        item.signed_distance_m(s.signed_distance_m);
        item.normal_device(s.normal_device);
        item.weight(s.weight);
        out.samples().push_back(item);
    }
    out.reference_force_device_n(in.reference_force_device_n);
    out.reference_moment_device_nm(in.reference_moment_device_nm);
    out.tracking(toIdl(in.tracking));
    return out;
}

ConversionResult fromIdl(const idl::ContactSurface& in, ContactSurface& out) {
    ConversionResult result;
    if (!fromIdl(in.header(), out.header, "ContactSurface", result)) {
        return result;
    }
    if (!fitsCapacity(in.samples().size(), out.samples, "ContactSurface.samples", result)) {
        return result;
    }
    out.samples.clear();
    for (const auto& s : in.samples()) {
        out.samples.push_back(
            ContactSample{s.p_device_m(), s.signed_distance_m(), s.normal_device(), s.weight()});
    }
    out.reference_force_device_n = in.reference_force_device_n();
    out.reference_moment_device_nm = in.reference_moment_device_nm();
    out.tracking = fromIdl(in.tracking());
    return result;
}

// ---- DeviceState ------------------------------------------------------------------------

idl::DeviceState toIdl(const DeviceState& in) {
    idl::DeviceState out;
    out.header(toIdl(in.header));
    out.joint_count(in.joint_count);
    out.joint_position_rad(in.joint_position_rad);
    out.joint_velocity_rad_per_s(in.joint_velocity_rad_per_s);
    out.actuator_count(in.actuator_count);
    out.actuator_position(in.actuator_position);
    out.actuator_force(in.actuator_force);
    out.platform_position_m(in.platform_position_m);
    out.platform_orientation_wxyz(in.platform_orientation_wxyz);
    out.status_bits(in.status_bits);
    return out;
}

ConversionResult fromIdl(const idl::DeviceState& in, DeviceState& out) {
    ConversionResult result;
    if (!fromIdl(in.header(), out.header, "DeviceState", result)) {
        return result;
    }
    out.joint_count = in.joint_count();
    out.joint_position_rad = in.joint_position_rad();
    out.joint_velocity_rad_per_s = in.joint_velocity_rad_per_s();
    out.actuator_count = in.actuator_count();
    out.actuator_position = in.actuator_position();
    out.actuator_force = in.actuator_force();
    out.platform_position_m = in.platform_position_m();
    out.platform_orientation_wxyz = in.platform_orientation_wxyz();
    out.status_bits = in.status_bits();
    return result;
}

// ---- HandPose ---------------------------------------------------------------------------

idl::HandPose toIdl(const HandPose& in) {
    idl::HandPose out;
    out.header(toIdl(in.header));
    out.wrist_position_m(in.wrist_position_m);
    out.wrist_orientation_wxyz(in.wrist_orientation_wxyz);
    out.joint_angles_rad().assign(in.joint_angles_rad.begin(), in.joint_angles_rad.end());
    out.confidence(in.confidence);
    return out;
}

ConversionResult fromIdl(const idl::HandPose& in, HandPose& out) {
    ConversionResult result;
    if (!fromIdl(in.header(), out.header, "HandPose", result)) {
        return result;
    }
    if (!fitsCapacity(in.joint_angles_rad().size(), out.joint_angles_rad,
                      "HandPose.joint_angles_rad", result)) {
        return result;
    }
    out.wrist_position_m = in.wrist_position_m();
    out.wrist_orientation_wxyz = in.wrist_orientation_wxyz();
    out.joint_angles_rad.clear();
    for (double angle : in.joint_angles_rad()) {
        out.joint_angles_rad.push_back(angle);
    }
    out.confidence = in.confidence();
    return result;
}

// ---- HapticStatus -----------------------------------------------------------------------

idl::HapticStatus toIdl(const HapticStatus& in) {
    idl::HapticStatus out;
    out.header(toIdl(in.header));
    out.state(toIdlEnum<idl::DaemonState>(in.state));
    copyString(in.rendering_method, out.rendering_method());
    copyString(in.version, out.version());
    copyString(in.config_digest, out.config_digest());
    out.uptime_s(in.uptime_s);

    idl::LoopStatistics loop;
    loop.rate_hz(in.loop.rate_hz);
    loop.ticks(in.loop.ticks);
    loop.overruns(in.loop.overruns);
    loop.overruns_read(in.loop.overruns_read);
    loop.overruns_compute(in.loop.overruns_compute);
    loop.overruns_write(in.loop.overruns_write);
    loop.period_us(toIdl(in.loop.period_us));
    loop.wakeup_latency_us(toIdl(in.loop.wakeup_latency_us));
    loop.tick_work_us(toIdl(in.loop.tick_work_us));
    out.loop(loop);

    for (const auto& d : in.devices) {
        idl::DeviceStatus item;
        copyString(d.device_id, item.device_id());
        item.kind(toIdlEnum<idl::DeviceKind>(d.kind));
        item.state(toIdlEnum<idl::DeviceRunState>(d.state));
        idl::CanCounters can;
        can.bus_state(toIdlEnum<idl::BusState>(d.can.bus_state));
        can.rx_frames(d.can.rx_frames);
        can.tx_frames(d.can.tx_frames);
        can.rx_errors(d.can.rx_errors);
        can.tx_errors(d.can.tx_errors);
        can.rejected_frames(d.can.rejected_frames);
        item.can(can);
        item.last_frame_age_ms(d.last_frame_age_ms);
        item.awaiting_enable(d.awaiting_enable);
        out.devices().push_back(item);
    }

    idl::SimLinkStatus link;
    link.transport(toIdlEnum<idl::SimTransport>(in.sim_link.transport));
    link.connected(in.sim_link.connected);
    link.age_ms(in.sim_link.age_ms);
    link.rate_hz(in.sim_link.rate_hz);
    link.received(in.sim_link.received);
    link.rejected(in.sim_link.rejected);
    link.rejected_by_reason(in.sim_link.rejected_by_reason);
    link.late_input_ticks(in.sim_link.late_input_ticks);
    out.sim_link(link);

    for (const auto& f : in.faults) {
        idl::Fault item;
        item.code(f.code);
        copyString(f.device_id, item.device_id());
        copyString(f.message, item.message());
        out.faults().push_back(item);
    }
    return out;
}

ConversionResult fromIdl(const idl::HapticStatus& in, HapticStatus& out) {
    ConversionResult result;
    if (!fromIdl(in.header(), out.header, "HapticStatus", result)) {
        return result;
    }
    if (!fitsCapacity(in.devices().size(), out.devices, "HapticStatus.devices", result) ||
        !fitsCapacity(in.faults().size(), out.faults, "HapticStatus.faults", result) ||
        !convertEnum(in.state(), DaemonState::kEstop, out.state, "HapticStatus.state", result) ||
        !convertEnum(in.sim_link().transport(), SimTransport::kDds, out.sim_link.transport,
                     "HapticStatus.sim_link.transport", result)) {
        return result;
    }
    copyString(in.rendering_method(), out.rendering_method);
    copyString(in.version(), out.version);
    copyString(in.config_digest(), out.config_digest);
    out.uptime_s = in.uptime_s();

    const auto& loop = in.loop();
    out.loop.rate_hz = loop.rate_hz();
    out.loop.ticks = loop.ticks();
    out.loop.overruns = loop.overruns();
    out.loop.overruns_read = loop.overruns_read();
    out.loop.overruns_compute = loop.overruns_compute();
    out.loop.overruns_write = loop.overruns_write();
    fromIdl(loop.period_us(), out.loop.period_us);
    fromIdl(loop.wakeup_latency_us(), out.loop.wakeup_latency_us);
    fromIdl(loop.tick_work_us(), out.loop.tick_work_us);

    out.devices.clear();
    for (const auto& d : in.devices()) {
        DeviceStatus item;
        copyString(d.device_id(), item.device_id);
        if (!convertEnum(d.kind(), DeviceKind::kThimble, item.kind, "DeviceStatus.kind", result) ||
            !convertEnum(d.state(), DeviceRunState::kFault, item.state, "DeviceStatus.state",
                         result) ||
            !convertEnum(d.can().bus_state(), BusState::kBusOff, item.can.bus_state,
                         "DeviceStatus.can.bus_state", result)) {
            return result;
        }
        item.can.rx_frames = d.can().rx_frames();
        item.can.tx_frames = d.can().tx_frames();
        item.can.rx_errors = d.can().rx_errors();
        item.can.tx_errors = d.can().tx_errors();
        item.can.rejected_frames = d.can().rejected_frames();
        item.last_frame_age_ms = d.last_frame_age_ms();
        item.awaiting_enable = d.awaiting_enable();
        out.devices.push_back(item);
    }

    const auto& link = in.sim_link();
    out.sim_link.connected = link.connected();
    out.sim_link.age_ms = link.age_ms();
    out.sim_link.rate_hz = link.rate_hz();
    out.sim_link.received = link.received();
    out.sim_link.rejected = link.rejected();
    out.sim_link.rejected_by_reason = link.rejected_by_reason();
    out.sim_link.late_input_ticks = link.late_input_ticks();

    out.faults.clear();
    for (const auto& f : in.faults()) {
        Fault item;
        item.code = f.code();
        copyString(f.device_id(), item.device_id);
        copyString(f.message(), item.message);
        out.faults.push_back(item);
    }
    return result;
}

// ---- HapticTelemetry --------------------------------------------------------------------

idl::HapticTelemetry toIdl(const HapticTelemetry& in) {
    idl::HapticTelemetry out;
    out.header(toIdl(in.header));
    out.samples().reserve(in.samples.size());
    for (const auto& s : in.samples) {
        idl::TelemetrySample item;
        item.tick(s.tick);
        item.stamp_ns(s.stamp_ns);
        item.device_index(s.device_index);
        item.device_kind(toIdlEnum<idl::DeviceKind>(s.device_kind));
        idl::ExoskeletonTelemetry exoskeleton;
        exoskeleton.actuator_force_cmd_n(s.exoskeleton.actuator_force_cmd_n);
        exoskeleton.actuator_force_n(s.exoskeleton.actuator_force_n);
        exoskeleton.joint_position_rad(s.exoskeleton.joint_position_rad);
        exoskeleton.proxy_position_rad(s.exoskeleton.proxy_position_rad);
        exoskeleton.reference_torque_nm(s.exoskeleton.reference_torque_nm);
        exoskeleton.reference_actuator_force_n(s.exoskeleton.reference_actuator_force_n);
        exoskeleton.ghost_torque_nm(s.exoskeleton.ghost_torque_nm);
        exoskeleton.energy_observer_j(s.exoskeleton.energy_observer_j);
        exoskeleton.environment_work_j(s.exoskeleton.environment_work_j);
        item.exoskeleton(exoskeleton);
        idl::ThimbleTelemetry thimble;
        thimble.servo_angle_cmd_rad(s.thimble.servo_angle_cmd_rad);
        thimble.servo_angle_rad(s.thimble.servo_angle_rad);
        thimble.platform_height_m(s.thimble.platform_height_m);
        thimble.platform_tilt_x_rad(s.thimble.platform_tilt_x_rad);
        thimble.platform_tilt_y_rad(s.thimble.platform_tilt_y_rad);
        thimble.reference_force_device_n(s.thimble.reference_force_device_n);
        thimble.reference_moment_device_nm(s.thimble.reference_moment_device_nm);
        thimble.pad_force_model_n(s.thimble.pad_force_model_n);
        thimble.pad_limit_flags(s.thimble.pad_limit_flags);
        item.thimble(thimble);
        item.tick_work_us(s.tick_work_us);
        item.read_us(s.read_us);
        item.write_us(s.write_us);
        item.wakeup_latency_us(s.wakeup_latency_us);
        item.tracking(toIdl(s.tracking));
        out.samples().push_back(item);
    }
    return out;
}

ConversionResult fromIdl(const idl::HapticTelemetry& in, HapticTelemetry& out) {
    ConversionResult result;
    if (!fromIdl(in.header(), out.header, "HapticTelemetry", result)) {
        return result;
    }
    if (!fitsCapacity(in.samples().size(), out.samples, "HapticTelemetry.samples", result)) {
        return result;
    }
    out.samples.clear();
    for (const auto& s : in.samples()) {
        TelemetrySample item;
        item.tick = s.tick();
        item.stamp_ns = s.stamp_ns();
        item.device_index = s.device_index();
        if (!convertEnum(s.device_kind(), DeviceKind::kThimble, item.device_kind,
                         "TelemetrySample.device_kind", result)) {
            return result;
        }
        item.exoskeleton.actuator_force_cmd_n = s.exoskeleton().actuator_force_cmd_n();
        item.exoskeleton.actuator_force_n = s.exoskeleton().actuator_force_n();
        item.exoskeleton.joint_position_rad = s.exoskeleton().joint_position_rad();
        item.exoskeleton.proxy_position_rad = s.exoskeleton().proxy_position_rad();
        item.exoskeleton.reference_torque_nm = s.exoskeleton().reference_torque_nm();
        item.exoskeleton.reference_actuator_force_n = s.exoskeleton().reference_actuator_force_n();
        item.exoskeleton.ghost_torque_nm = s.exoskeleton().ghost_torque_nm();
        item.exoskeleton.energy_observer_j = s.exoskeleton().energy_observer_j();
        item.exoskeleton.environment_work_j = s.exoskeleton().environment_work_j();
        item.thimble.servo_angle_cmd_rad = s.thimble().servo_angle_cmd_rad();
        item.thimble.servo_angle_rad = s.thimble().servo_angle_rad();
        item.thimble.platform_height_m = s.thimble().platform_height_m();
        item.thimble.platform_tilt_x_rad = s.thimble().platform_tilt_x_rad();
        item.thimble.platform_tilt_y_rad = s.thimble().platform_tilt_y_rad();
        item.thimble.reference_force_device_n = s.thimble().reference_force_device_n();
        item.thimble.reference_moment_device_nm = s.thimble().reference_moment_device_nm();
        item.thimble.pad_force_model_n = s.thimble().pad_force_model_n();
        item.thimble.pad_limit_flags = s.thimble().pad_limit_flags();
        item.tick_work_us = s.tick_work_us();
        item.read_us = s.read_us();
        item.write_us = s.write_us();
        item.wakeup_latency_us = s.wakeup_latency_us();
        item.tracking = fromIdl(s.tracking());
        out.samples.push_back(item);
    }
    return result;
}

// ---- HapticCommand and its reply --------------------------------------------------------

idl::HapticCommand toIdl(const HapticCommand& in) {
    idl::HapticCommand out;
    out.header(toIdl(in.header));
    out.request_id(in.request_id);
    out.kind(toIdlEnum<idl::CommandKind>(in.kind));
    copyString(in.device_id, out.device_id());
    copyString(in.argument, out.argument());
    return out;
}

ConversionResult fromIdl(const idl::HapticCommand& in, HapticCommand& out) {
    ConversionResult result;
    if (!fromIdl(in.header(), out.header, "HapticCommand", result)) {
        return result;
    }
    if (!convertEnum(in.kind(), CommandKind::kClearFault, out.kind, "HapticCommand.kind", result)) {
        return result;
    }
    out.request_id = in.request_id();
    copyString(in.device_id(), out.device_id);
    copyString(in.argument(), out.argument);
    return result;
}

idl::HapticCommandReply toIdl(const HapticCommandReply& in) {
    idl::HapticCommandReply out;
    out.header(toIdl(in.header));
    out.request_id(in.request_id);
    out.accepted(in.accepted);
    copyString(in.message, out.message());
    return out;
}

ConversionResult fromIdl(const idl::HapticCommandReply& in, HapticCommandReply& out) {
    ConversionResult result;
    if (!fromIdl(in.header(), out.header, "HapticCommandReply", result)) {
        return result;
    }
    out.request_id = in.request_id();
    out.accepted = in.accepted();
    copyString(in.message(), out.message);
    return result;
}

// ---- SimStatus --------------------------------------------------------------------------

idl::SimStatus toIdl(const SimStatus& in) {
    idl::SimStatus out;
    out.header(toIdl(in.header));
    out.rate_hz(in.rate_hz);
    out.steps(in.steps);
    out.step_time_us(toIdl(in.step_time_us));
    out.node_count(in.node_count);
    out.element_count(in.element_count);
    out.solver_residual(in.solver_residual);
    out.solver_iterations(in.solver_iterations);
    out.energy_j(in.energy_j);
    copyString(in.model, out.model());
    out.steps_zeroed(in.steps_zeroed);
    out.steps_substepped(in.steps_substepped);
    out.inputs_rejected(in.inputs_rejected);
    copyString(in.last_rejection, out.last_rejection());
    out.steps_rescaled(in.steps_rescaled);
    return out;
}

ConversionResult fromIdl(const idl::SimStatus& in, SimStatus& out) {
    ConversionResult result;
    if (!fromIdl(in.header(), out.header, "SimStatus", result)) {
        return result;
    }
    out.rate_hz = in.rate_hz();
    out.steps = in.steps();
    fromIdl(in.step_time_us(), out.step_time_us);
    out.node_count = in.node_count();
    out.element_count = in.element_count();
    out.solver_residual = in.solver_residual();
    out.solver_iterations = in.solver_iterations();
    out.energy_j = in.energy_j();
    copyString(in.model(), out.model);
    out.steps_zeroed = in.steps_zeroed();
    out.steps_substepped = in.steps_substepped();
    out.inputs_rejected = in.inputs_rejected();
    copyString(in.last_rejection(), out.last_rejection);
    out.steps_rescaled = in.steps_rescaled();
    return result;
}

}  // namespace haptic::msgs
