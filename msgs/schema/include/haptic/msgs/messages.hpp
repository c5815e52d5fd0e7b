#pragma once

// Fixed-size, trivially copyable twins of the DDS types generated from msgs/idl/*.idl.
// They are what iceoryx carries between processes on one host (zero copy, no allocation on
// the RT side). Field names, order and capacities follow the IDL one for one; the
// round-trip test in tests/msgs/ fails if either side changes alone.
//
// Conventions: stamps are CLOCK_MONOTONIC nanoseconds of when the content was computed;
// units and frames are in the field names; quaternions are (w, x, y, z).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <tuple>
#include <type_traits>

#include "haptic/msgs/bounded_array.hpp"
#include "haptic/msgs/capacities.hpp"
#include "haptic/msgs/fixed_string.hpp"

namespace haptic::msgs {

using DeviceId = FixedString<kIdCapacity>;

// The layout of the messages: raise kSchemaVersion with any change to a message here or in
// idl/ (a field added, removed, moved or resized, a capacity). Every message carries kSchema
// first (MessageHeader, first member of each), and its readers refuse another one: over DDS
// (conversions), iceoryx (hapticd's sim input validation, handsim's device states) and the
// control socket. Peers from two releases, say a handsim on another PC, would otherwise read
// each other's fields as something else. The mark in the upper half keeps a release from
// before the field (whose header began with its sequence number, 1, 2, ...) from passing for
// version 1. tests/msgs/schema_version_test.cpp records the layout the version stands for.
inline constexpr std::uint32_t kSchemaMark = 0x48500000;  // "HP"
inline constexpr std::uint16_t kSchemaVersion = 1;
inline constexpr std::uint32_t kSchema = kSchemaMark | kSchemaVersion;

struct MessageHeader {
    std::uint32_t schema{kSchema};
    std::uint64_t seq{0};
    std::int64_t stamp_ns{0};
    DeviceId source_id{};  // device name or scene name
    friend bool operator==(const MessageHeader&, const MessageHeader&) = default;
};

// The tracker sample a sim output follows, for the tracker-to-force latency: zero when the
// hand is scripted or replayed. Both CLOCK_MONOTONIC of the sim's host.
struct TrackingOrigin {
    std::int64_t sampled_ns{0};   // the sample's own stamp (HandPose header.stamp_ns)
    std::int64_t received_ns{0};  // when the sim's reader received it
    friend bool operator==(const TrackingOrigin&, const TrackingOrigin&) = default;
};

struct Percentiles {
    double p50{0.0};
    double p99{0.0};
    double max{0.0};
    friend bool operator==(const Percentiles&, const Percentiles&) = default;
};

// ---- sim -> daemon -------------------------------------------------------------------

// The contact behind a constraint row, so that hapticd can evaluate the row on the finger's
// kinematics instead of its linearisation (subspace, docs/algorithms.md §5.4). Vectors are in
// any one frame, relative to the contact point p at q_ref_rad: the point is carried by joints
// 0..joints-1, joint j turning about axis[j] through p - lever_m[j], so that with
//   x(q) = the point moved by the joints from q_ref_rad to q   (x(q_ref_rad) = p)
//   g(q) = normal . (x(q) - p) + gap_m
// the row is g's linearisation at q_ref_rad: a_j = normal . (axis[j] x lever_m[j]),
// b = a . q_ref_rad - gap_m. Relative vectors keep a row whole under the blend between frames.
// joints = 0: no contact is known, the row is all there is.
struct ContactKinematics {
    std::int16_t joints{0};
    double gap_m{0.0};  // g(q_ref_rad): the point's signed distance, negative inside
    std::array<double, 3> normal{};
    std::array<double, kMaxContactJoints> q_ref_rad{};
    std::array<std::array<double, 3>, kMaxContactJoints> axis{};
    std::array<std::array<double, 3>, kMaxContactJoints> lever_m{};
    friend bool operator==(const ContactKinematics&, const ContactKinematics&) = default;
};

// One linearised constraint a^T q >= b in device joint space.
struct LinearConstraint {
    std::array<double, kMaxJointDofs> a{};
    double b{0.0};
    ContactKinematics contact{};
    friend bool operator==(const LinearConstraint&, const LinearConstraint&) = default;
};

// Per kinesthetic device: the simulated (constrained) configuration and the constraints that
// let the daemon re-solve the proxy at 1 kHz between sim frames.
struct ConstraintSet {
    MessageHeader header{};
    std::uint16_t dof{0};
    std::array<double, kMaxJointDofs> q_sim_rad{};
    BoundedArray<LinearConstraint, kMaxConstraints> constraints{};
    // The fully actuated reference: joint torques the object's contact applies to the
    // simulated finger (sum of J^T f); what the user should feel.
    std::array<double, kMaxJointDofs> reference_torque_nm{};
    TrackingOrigin tracking{};
    friend bool operator==(const ConstraintSet&, const ConstraintSet&) = default;
};

struct ContactSample {
    std::array<double, 3> p_device_m{};
    double signed_distance_m{0.0};  // negative = penetrating the virtual object
    std::array<double, 3> normal_device{};
    double weight{0.0};
    friend bool operator==(const ContactSample&, const ContactSample&) = default;
};

// Per tactile device: finger-pad samples in the device base frame, the matching target of
// the tactile optimiser.
struct ContactSurface {
    MessageHeader header{};
    BoundedArray<ContactSample, kMaxContactSamples> samples{};
    // The reference: net contact force and moment (about the device origin) the object applies
    // to the simulated pad, device frame.
    std::array<double, 3> reference_force_device_n{};
    std::array<double, 3> reference_moment_device_nm{};
    TrackingOrigin tracking{};
    friend bool operator==(const ContactSurface&, const ContactSurface&) = default;
};

// ---- daemon -> sim -------------------------------------------------------------------

enum class DeviceStatusBit : std::uint32_t {
    kOnline = 1U << 0,
    kRendering = 1U << 1,
    kSafeState = 1U << 2,
    kFault = 1U << 3,
    kStaleSimInput = 1U << 4,
};

struct DeviceState {
    MessageHeader header{};
    std::uint16_t joint_count{0};
    std::array<double, kMaxJointDofs> joint_position_rad{};
    std::array<double, kMaxJointDofs> joint_velocity_rad_per_s{};
    std::uint16_t actuator_count{0};
    std::array<double, kMaxActuators> actuator_position{};  // m (linear) or rad (rotary)
    std::array<double, kMaxActuators> actuator_force{};     // N (linear) or N m (rotary)
    std::array<double, 3> platform_position_m{};
    std::array<double, 4> platform_orientation_wxyz{1.0, 0.0, 0.0, 0.0};
    std::uint32_t status_bits{0};
    friend bool operator==(const DeviceState&, const DeviceState&) = default;
};

// ---- tracker -> sim ------------------------------------------------------------------

struct HandPose {
    MessageHeader header{};
    std::array<double, 3> wrist_position_m{};
    std::array<double, 4> wrist_orientation_wxyz{1.0, 0.0, 0.0, 0.0};
    BoundedArray<double, kMaxHandJointAngles> joint_angles_rad{};
    double confidence{0.0};
    friend bool operator==(const HandPose&, const HandPose&) = default;
};

// ---- daemon status -------------------------------------------------------------------

enum class DaemonState : std::uint32_t { kInit, kIdle, kRendering, kFault, kEstop };
enum class DeviceKind : std::uint32_t { kExoskeleton, kThimble };
enum class DeviceRunState : std::uint32_t { kOffline, kReady, kActive, kSafe, kFault };
enum class BusState : std::uint32_t {
    kUnknown,
    kErrorActive,
    kErrorWarning,
    kErrorPassive,
    kBusOff
};
enum class SimTransport : std::uint32_t { kIceoryx, kDds };

// Why hapticd rejected a message from the sim. Counted per reason in SimLinkStatus; a
// rejected message never reaches a device: NaN/Inf and out-of-range values stop where they
// enter (hapticd's validate()).
enum class SimInputRejection : std::uint8_t {
    kNone,
    kWrongDevice,           // source_id names another device
    kDofMismatch,           // dof differs from the device's joint count
    kNonFinite,             // NaN or Inf anywhere
    kCountOverCapacity,     // a count larger than its array (corrupt shared memory)
    kDegenerateConstraint,  // a constraint normal of zero length, or a contact beyond 1 m / 10 rad
    kBadNormal,             // a contact normal that is not unit length
    kNegativeWeight,
    kNotNewer,     // its header.seq does not advance (and it is no restart): a replay or duplicate
    kDelayed,      // older than sim_timeout_ns by its stamp (see DaemonCore::freshness())
    kBadStamp,     // header.stamp_ns is 0 or negative
    kStampAhead,   // stamped ahead of the sim's learnt clock by more than sim_timeout_ns
    kOtherSchema,  // header.schema is not kSchema: a sim from another release
    kCount_,
};
// SimLinkStatus::rejected_by_reason has one count per reason, kNone left out.
inline constexpr std::size_t kSimInputRejectionReasons =
    static_cast<std::size_t>(SimInputRejection::kCount_) - 1;
[[nodiscard]] constexpr std::size_t reasonIndex(SimInputRejection reason) noexcept {
    return static_cast<std::size_t>(reason) - 1;
}
[[nodiscard]] constexpr SimInputRejection reasonAt(std::size_t index) noexcept {
    return static_cast<SimInputRejection>(index + 1);
}

struct LoopStatistics {
    double rate_hz{0.0};
    std::uint64_t ticks{0};
    std::uint64_t overruns{0};
    std::uint64_t overruns_read{0};  // overruns whose largest share was the CAN read
    std::uint64_t overruns_compute{0};
    std::uint64_t overruns_write{0};
    Percentiles period_us{};
    Percentiles wakeup_latency_us{};
    Percentiles tick_work_us{};  // the whole tick: read + compute + write
    friend bool operator==(const LoopStatistics&, const LoopStatistics&) = default;
};

struct CanCounters {
    BusState bus_state{BusState::kUnknown};
    std::uint64_t rx_frames{0};
    std::uint64_t tx_frames{0};
    std::uint64_t rx_errors{0};
    std::uint64_t tx_errors{0};
    std::uint64_t rejected_frames{0};
    friend bool operator==(const CanCounters&, const CanCounters&) = default;
};

struct DeviceStatus {
    DeviceId device_id{};
    DeviceKind kind{DeviceKind::kExoskeleton};
    DeviceRunState state{DeviceRunState::kOffline};
    CanCounters can{};
    double last_frame_age_ms{0.0};
    // Its sim input was lost longer than loop.sim_rearm_after_ms while RENDERING: it renders
    // again only after a new `enable`.
    bool awaiting_enable{false};
    friend bool operator==(const DeviceStatus&, const DeviceStatus&) = default;
};

struct SimLinkStatus {
    SimTransport transport{SimTransport::kIceoryx};
    bool connected{false};
    double age_ms{0.0};
    double rate_hz{0.0};
    std::uint64_t received{0};
    std::uint64_t rejected{0};
    // The rejected messages by reason, indexed by reasonIndex(); they add up to `rejected`.
    std::array<std::uint64_t, kSimInputRejectionReasons> rejected_by_reason{};
    // Ticks since start on which some device's input was older than the fade start (3/4 of
    // sim_timeout_ms) but not yet timed out: the sim is alive but slower than the fade allows.
    std::uint64_t late_input_ticks{0};
    friend bool operator==(const SimLinkStatus&, const SimLinkStatus&) = default;
};

struct Fault {
    std::uint32_t code{0};
    DeviceId device_id{};
    FixedString<kShortTextCapacity> message{};
    friend bool operator==(const Fault&, const Fault&) = default;
};

struct HapticStatus {
    MessageHeader header{};
    DaemonState state{DaemonState::kInit};
    DeviceId rendering_method{};
    double uptime_s{0.0};
    LoopStatistics loop{};
    BoundedArray<DeviceStatus, kMaxStatusDevices> devices{};
    SimLinkStatus sim_link{};
    BoundedArray<Fault, kMaxStatusFaults> faults{};
    DeviceId version{};                               // hapticd's version
    FixedString<kShortTextCapacity> config_digest{};  // config::configurationDigest
    friend bool operator==(const HapticStatus&, const HapticStatus&) = default;
};

// ---- daemon telemetry ----------------------------------------------------------------

// The exoskeleton's part of a telemetry sample (zero for a thimble).
struct ExoskeletonTelemetry {
    double actuator_force_cmd_n{0.0};  // force commanded to the linear actuator
    double actuator_force_n{0.0};      // force the actuator reports: what the finger feels
    std::array<double, kMaxJointDofs> joint_position_rad{};   // measured finger joints
    std::array<double, kMaxJointDofs> proxy_position_rad{};   // the proxy the coupling pulls to
    std::array<double, kMaxJointDofs> reference_torque_nm{};  // the sim's reference
    double reference_actuator_force_n{0.0};  // B^+ reference_torque_nm: the force to compare
    // The felt joint torque (J^T F of the reported actuator force) orthogonal to the reference.
    std::array<double, kMaxJointDofs> ghost_torque_nm{};
    double energy_observer_j{0.0};   // the port's passivity observer
    double environment_work_j{0.0};  // work the sim's moving objects did on the coupling
    friend bool operator==(const ExoskeletonTelemetry&, const ExoskeletonTelemetry&) = default;
};

// The thimble's part of a telemetry sample (zero for an exoskeleton).
struct ThimbleTelemetry {
    std::array<double, kThimbleServos> servo_angle_cmd_rad{};  // servo targets sent this tick
    std::array<double, kThimbleServos> servo_angle_rad{};      // measured servo angles
    double platform_height_m{0.0};                             // the optimiser's platform pose
    double platform_tilt_x_rad{0.0};
    double platform_tilt_y_rad{0.0};
    std::array<double, 3> reference_force_device_n{};  // the sim's reference on the pad
    std::array<double, 3> reference_moment_device_nm{};
    double pad_force_model_n{0.0};    // the pad model's force for the plate pose commanded
    std::uint8_t pad_limit_flags{0};  // tactile::PadFlag bits: which safety limit held it back
    friend bool operator==(const ThimbleTelemetry&, const ThimbleTelemetry&) = default;
};

struct TelemetrySample {
    std::uint64_t tick{0};
    std::int64_t stamp_ns{0};
    std::uint16_t device_index{0};
    DeviceKind device_kind{DeviceKind::kExoskeleton};  // which of the two parts applies
    ExoskeletonTelemetry exoskeleton{};
    ThimbleTelemetry thimble{};
    double tick_work_us{0.0};  // the whole tick: read + compute + write
    double read_us{0.0};       // of which CAN read, sim inputs, commands
    double write_us{0.0};      // of which CAN write, DeviceState hand-off
    double wakeup_latency_us{0.0};
    // The tracker sample behind the sim input this tick's command was computed from.
    TrackingOrigin tracking{};
    friend bool operator==(const TelemetrySample&, const TelemetrySample&) = default;
};

struct HapticTelemetry {
    MessageHeader header{};
    BoundedArray<TelemetrySample, kMaxTelemetrySamples> samples{};
    friend bool operator==(const HapticTelemetry&, const HapticTelemetry&) = default;
};

// ---- commands ------------------------------------------------------------------------

enum class CommandKind : std::uint32_t { kEnable, kDisable, kSetMethod, kEstop, kClearFault };

struct HapticCommand {
    MessageHeader header{};
    std::uint64_t request_id{0};
    CommandKind kind{CommandKind::kDisable};
    DeviceId device_id{};  // empty: every device
    DeviceId argument{};   // method name for kSetMethod
    friend bool operator==(const HapticCommand&, const HapticCommand&) = default;
};

struct HapticCommandReply {
    MessageHeader header{};
    std::uint64_t request_id{0};
    bool accepted{false};
    FixedString<kLongTextCapacity> message{};
    friend bool operator==(const HapticCommandReply&, const HapticCommandReply&) = default;
};

// ---- sim status ----------------------------------------------------------------------

struct SimStatus {
    MessageHeader header{};
    double rate_hz{0.0};
    std::uint64_t steps{0};
    Percentiles step_time_us{};
    std::uint32_t node_count{0};
    std::uint32_t element_count{0};
    double solver_residual{0.0};
    std::uint32_t solver_iterations{0};
    double energy_j{0.0};
    FixedString<kModelNameCapacity> model{};
    // Since handsim started: steps held with no finite state to advance to (positions kept,
    // velocities 0: a frozen frame; a finite step never gets here), steps the energy guard
    // split into substeps, steps whose energy rose and had their velocities scaled down
    // (positions from the Newton result), and refused tracking inputs with the latest reason.
    std::uint64_t steps_zeroed{0};
    std::uint64_t steps_substepped{0};
    std::uint64_t inputs_rejected{0};
    FixedString<kShortTextCapacity> last_rejection{};
    std::uint64_t steps_rescaled{0};
    friend bool operator==(const SimStatus&, const SimStatus&) = default;
};

// Every twin must be shareable through RouDi: trivially copyable and within the largest
// mempool chunk.
template <typename T>
inline constexpr bool kIsShmMessage =
    std::is_trivially_copyable_v<T>&& std::is_standard_layout_v<T> &&
    sizeof(T) <= kMaxShmPayloadBytes;

// Every twin hapticd and handsim put through RouDi, each with its name for error messages:
// the one list the checks here and the RouDi configuration check (haptic/ipc) walk.
template <typename Message>
struct ShmMessageType {
    using type = Message;
    std::string_view name;
};
inline constexpr std::tuple kShmMessageTypes{
    ShmMessageType<ConstraintSet>{"ConstraintSet"},
    ShmMessageType<ContactSurface>{"ContactSurface"},
    ShmMessageType<DeviceState>{"DeviceState"},
    ShmMessageType<HandPose>{"HandPose"},
    ShmMessageType<HapticStatus>{"HapticStatus"},
    ShmMessageType<HapticTelemetry>{"HapticTelemetry"},
    ShmMessageType<HapticCommand>{"HapticCommand"},
    ShmMessageType<HapticCommandReply>{"HapticCommandReply"},
    ShmMessageType<SimStatus>{"SimStatus"},
};
static_assert(std::apply(
    [](auto... message) { return (kIsShmMessage<typename decltype(message)::type> && ...); },
    kShmMessageTypes));
// The header, and so its schema, at the start of every message: readable whatever the rest
// of another release's layout.
static_assert(std::apply(
    [](auto... message) {
        return ((offsetof(typename decltype(message)::type, header) == 0) && ...);
    },
    kShmMessageTypes));
static_assert(offsetof(MessageHeader, schema) == 0);

}  // namespace haptic::msgs
