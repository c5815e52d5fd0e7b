// One real malformed file per class of mistake. Each test pins the file, line, key and the
// expectation the message states, because that message is the whole user interface of a
// config error.

#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>

#include "haptic/config/config.hpp"
#include "haptic/config/virtual_user.hpp"
#include "test_support.hpp"

namespace haptic::config {
namespace {

using test::configErrorOf;
using test::kDataDir;
using test::lineOf;
using test::resolved;

struct Expected {
    std::string file;
    int line;
    int column;  // -1: not checked
    std::string key;
    std::string substring;
};

void expectError(const std::optional<ConfigError>& error, const Expected& expected) {
    ASSERT_TRUE(error.has_value());
    const std::string what = error->what();
    EXPECT_EQ(error->file(), expected.file) << what;
    EXPECT_EQ(error->line(), expected.line) << what;
    if (expected.column >= 0) {
        EXPECT_EQ(error->column(), expected.column) << what;
    }
    EXPECT_EQ(error->key(), expected.key) << what;
    EXPECT_NE(what.find(expected.substring), std::string::npos)
        << "'" << expected.substring << "' not in: " << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "what() must be one line: " << what;

    // "<file>:<line>[:<col>]: <message>"
    std::string prefix = expected.file;
    if (error->line() > 0) {
        prefix += ":" + std::to_string(error->line());
        if (error->column() > 0) {
            prefix += ":" + std::to_string(error->column());
        }
    }
    EXPECT_EQ(what.rfind(prefix + ": ", 0), 0U) << what;
    EXPECT_EQ(what, prefix + ": " + error->message());
}

std::optional<ConfigError> daemonError(const std::string& name) {
    return configErrorOf([&] { (void)loadDaemonConfig(kDataDir / name); });
}
std::optional<ConfigError> deviceError(const std::string& name) {
    return configErrorOf([&] { (void)loadDeviceConfig(kDataDir / "devices" / name); });
}
std::optional<ConfigError> sceneError(const std::string& name) {
    return configErrorOf([&] { (void)loadSceneConfig(kDataDir / "scenes" / name); });
}
std::optional<ConfigError> simError(const std::string& name) {
    return configErrorOf([&] { (void)loadSimConfig(kDataDir / name); });
}
std::string data(const std::string& name) {
    return (kDataDir / name).string();
}

// --- file level ----------------------------------------------------------------------------

TEST(ConfigFileErrors, MissingFileNamesPathAndErrno) {
    expectError(daemonError("no_such_daemon.yaml"),
                {data("no_such_daemon.yaml"), 0, 0, "", std::strerror(ENOENT)});
}

TEST(ConfigFileErrors, DirectoryIsNotAFile) {
    expectError(configErrorOf([] { (void)loadDaemonConfig(kDataDir / "devices"); }),
                {data("devices"), 0, 0, "", std::strerror(EISDIR)});
}

TEST(ConfigFileErrors, YamlSyntaxErrorHasPositionAndParserMessage) {
    // The flow list opened on the devices line is never closed; yaml-cpp notices on the
    // next line, where the block map continues.
    expectError(daemonError("syntax_error.yaml"),
                {data("syntax_error.yaml"), lineOf(kDataDir / "syntax_error.yaml", "sim_link:"), -1,
                 "", "YAML syntax error: end of sequence flow not found"});
}

TEST(ConfigFileErrors, EmptyFile) {
    expectError(daemonError("empty.yaml"), {data("empty.yaml"), 0, 0, "", "empty file"});
}

TEST(ConfigFileErrors, RootMustBeAMap) {
    expectError(
        daemonError("root_is_list.yaml"),
        {data("root_is_list.yaml"), 1, 1, "", "expected a map of settings, got a list of 2 items"});
}

TEST(ConfigFileErrors, OnlyOneDocument) {
    expectError(daemonError("multi_document.yaml"),
                {data("multi_document.yaml"), 3, 1, "", "expected a single YAML document, got 2"});
}

TEST(ConfigFileErrors, DuplicateKeyIsRejected) {
    const auto file = kDataDir / "duplicate_key.yaml";
    expectError(daemonError("duplicate_key.yaml"),
                {data("duplicate_key.yaml"), lineOf(file, "rate_hz: 500"), 3, "loop.rate_hz",
                 "loop.rate_hz: expected each key once, got it again (first at line " +
                     std::to_string(lineOf(file, "rate_hz: 1000")) + ")"});
}

// --- unknown keys ----------------------------------------------------------------------------

TEST(ConfigUnknownKeys, TopLevelTypoListsAllowedKeys) {
    expectError(
        daemonError("unknown_key_top_level.yaml"),
        {data("unknown_key_top_level.yaml"), 1, 1, "log_levle",
         "unknown key 'log_levle' (allowed: log_level, loop, devices, estop_relay, control, "
         "sim_link, dds, iceoryx)"});
}

TEST(ConfigUnknownKeys, NestedTypoHasDottedPath) {
    expectError(
        daemonError("unknown_key_nested.yaml"),
        {data("unknown_key_nested.yaml"), lineOf(kDataDir / "unknown_key_nested.yaml", "rate_hx"),
         3, "loop.rate_hx",
         "unknown key 'loop.rate_hx' (allowed: rate_hz, realtime, priority, "
         "cpu_affinity, cpu_latency_us, sim_timeout_ms, sim_rearm_after_ms, status_rate_hz, "
         "telemetry_decimation, overrun_limit, overrun_window_ms)"});
}

TEST(ConfigUnknownKeys, ThimbleKeyInExoskeletonFile) {
    const auto file = kDataDir / "devices/thimble_key_on_exoskeleton.yaml";
    expectError(deviceError("thimble_key_on_exoskeleton.yaml"),
                {file.string(), lineOf(file, "geometry:"), 1, "geometry",
                 "allowed: name, type, can, safety, actuator, finger, linkage, rendering)"});
}

// handsim has no substeps under its real-time limits, so the solver block does not offer them.
TEST(ConfigUnknownKeys, SolverKeyHandsimDoesNotOffer) {
    const auto file = kDataDir / "scenes/solver_unknown_key.yaml";
    expectError(sceneError("solver_unknown_key.yaml"),
                {file.string(), lineOf(file, "max_substep_depth"), 3, "solver.max_substep_depth",
                 "unknown key 'solver.max_substep_depth' (allowed: newton_iterations, "
                 "pcg_max_iterations, helper_thread)"});
}

TEST(ConfigOutOfRange, SolverNeedsAtLeastOneNewtonIteration) {
    const auto file = kDataDir / "scenes/solver_out_of_range.yaml";
    expectError(sceneError("solver_out_of_range.yaml"),
                {file.string(), lineOf(file, "newton_iterations"), 22, "solver.newton_iterations",
                 "expected an integer in [1, 10], got 0"});
}

TEST(ConfigUnknownKeys, SizeKeyOfAnotherShape) {
    const auto file = kDataDir / "scenes/shape_unknown_key.yaml";
    expectError(
        sceneError("shape_unknown_key.yaml"),
        {file.string(), lineOf(file, "half_extents_m: [0.01"), 5, "objects[2].half_extents_m",
         "unknown key 'objects[2].half_extents_m' (allowed: name, shape, pose, radius_m, "
         "mass_kg, friction)"});
}

TEST(ConfigUnknownKeys, PlanesHaveNoMass) {
    const auto file = kDataDir / "scenes/plane_with_mass.yaml";
    expectError(sceneError("plane_with_mass.yaml"),
                {file.string(), lineOf(file, "mass_kg: 1.0"), 5, "objects[0].mass_kg",
                 "(allowed: name, shape, pose, friction)"});
}

TEST(ConfigUnknownKeys, WholeHandModelTakesNoFinger) {
    const auto file = kDataDir / "scenes/finger_on_hand_model.yaml";
    expectError(sceneError("finger_on_hand_model.yaml"),
                {file.string(), lineOf(file, "finger: index"), 3, "hand.finger",
                 "unknown key 'hand.finger' (allowed: model, fingers, resolution, anthropometry)"});
}

// --- wrong types -----------------------------------------------------------------------------

TEST(ConfigWrongTypes, StringWhereIntegerExpected) {
    expectError(daemonError("wrong_type_string_for_int.yaml"),
                {data("wrong_type_string_for_int.yaml"), 3, 12, "loop.rate_hz",
                 "loop.rate_hz: expected an integer in [100, 4000], got the string 'fast'"});
}

TEST(ConfigWrongTypes, FloatWhereIntegerExpected) {
    const auto file = kDataDir / "wrong_type_float_for_int.yaml";
    expectError(daemonError("wrong_type_float_for_int.yaml"),
                {file.string(), lineOf(file, "priority:"), 13, "loop.priority",
                 "expected an integer in [1, 99], got 80.5"});
}

TEST(ConfigWrongTypes, QuotedNumberIsAString) {
    expectError(
        daemonError("wrong_type_quoted_number.yaml"),
        {data("wrong_type_quoted_number.yaml"), 3, 12, "loop.rate_hz", "got the string '1000'"});
}

TEST(ConfigWrongTypes, ListWhereScalarExpected) {
    const auto file = kDataDir / "wrong_type_list_for_scalar.yaml";
    expectError(daemonError("wrong_type_list_for_scalar.yaml"),
                {file.string(), lineOf(file, "transport:"), 14, "sim_link.transport",
                 "expected one of iceoryx|dds, got a list of 1 item"});
}

TEST(ConfigWrongTypes, YesIsNotABoolean) {
    const auto file = kDataDir / "devices/wrong_type_bool.yaml";
    expectError(deviceError("wrong_type_bool.yaml"),
                {file.string(), lineOf(file, "fd: yes"), 7, "can.fd",
                 "can.fd: expected true or false, got the string 'yes'"});
}

TEST(ConfigWrongTypes, TheSolversHelperThreadIsTrueOrFalse) {
    const auto file = kDataDir / "scenes/solver_helper_thread_not_boolean.yaml";
    expectError(sceneError("solver_helper_thread_not_boolean.yaml"),
                {file.string(), lineOf(file, "helper_thread"), 18, "solver.helper_thread",
                 "solver.helper_thread: expected true or false, got the string 'sometimes'"});
}

TEST(ConfigWrongTypes, StringWhereNumberExpected) {
    const auto file = kDataDir / "devices/wrong_type_string_for_number.yaml";
    expectError(deviceError("wrong_type_string_for_number.yaml"),
                {file.string(), lineOf(file, "strong"), 16, "safety.max_force_n",
                 "expected a number in (0, 100], got the string 'strong'"});
}

// --- ranges and non-finite values -----------------------------------------------------------

TEST(ConfigOutOfRange, IntegerAboveMaximum) {
    expectError(daemonError("out_of_range.yaml"),
                {data("out_of_range.yaml"), 3, 12, "loop.rate_hz",
                 "loop.rate_hz: expected an integer in [100, 4000], got 50000"});
}

// Past 10 ms the request would keep no CPU out of any idle state a PC has: a typo of -1 or 0.
TEST(ConfigOutOfRange, CpuLatencyBeyondAnyIdleState) {
    const auto file = kDataDir / "cpu_latency_out_of_range.yaml";
    expectError(daemonError("cpu_latency_out_of_range.yaml"),
                {file.string(), lineOf(file, "cpu_latency_us"), 19, "loop.cpu_latency_us",
                 "expected an integer in [-1, 10000], got 20000"});
}

TEST(ConfigOutOfRange, MillimetresWrittenWhereMetresExpected) {
    const auto file = kDataDir / "devices/out_of_range_mm_for_m.yaml";
    expectError(deviceError("out_of_range_mm_for_m.yaml"),
                {file.string(), lineOf(file, "crank_length_m"), 19, "geometry.crank_length_m",
                 "expected a number in (0, 0.1], got 10"});
}

TEST(ConfigOutOfRange, CanIdBeyondElevenBits) {
    const auto file = kDataDir / "devices/can_id_out_of_range.yaml";
    expectError(deviceError("can_id_out_of_range.yaml"),
                {file.string(), lineOf(file, "command_id"), 15, "can.command_id",
                 "expected an integer in [0x0, 0x7ff], got 0x801"});
}

// Past 100 ms a device no longer watches its host: a finger would carry the last force that
// long after hapticd died.
TEST(ConfigOutOfRange, CommandTimeoutLongerThanTheDeviceMayWait) {
    const auto file = kDataDir / "devices/command_timeout_too_long.yaml";
    expectError(deviceError("command_timeout_too_long.yaml"),
                {file.string(), lineOf(file, "command_timeout_ms"), 23, "can.command_timeout_ms",
                 "expected an integer in [2, 100], got 250"});
}

// A re-arm limit below the sim timeout would demand an enable after every fade.
TEST(ConfigOutOfRange, RearmLimitShorterThanTheSimTimeout) {
    const auto file = kDataDir / "rearm_shorter_than_timeout.yaml";
    expectError(daemonError("rearm_shorter_than_timeout.yaml"),
                {file.string(), lineOf(file, "sim_rearm_after_ms"), 23, "loop.sim_rearm_after_ms",
                 "expected an integer in [20, 60000], got 10"});
}

// exo_ok.yaml (2000 N/m, the actuator's own damping 10 N s/m) is passive at 1 kHz (b must
// exceed K T / 2 = 1 N s/m plus the rendered damping) but not at 100 Hz (10 N s/m plus it):
// the error names the device file's stiffness key, since that is what to lower.
TEST(ConfigPassivityMargin, AStiffnessNotPassiveAtTheLoopRateNamesTheDeviceKey) {
    const auto device = kDataDir / "devices/exo_ok.yaml";
    expectError(daemonError("not_passive_at_loop_rate.yaml"),
                {device.string(), lineOf(device, "max_stiffness_n_per_m"), 26,
                 "safety.max_stiffness_n_per_m", "not passive at loop.rate_hz 100"});
    // The same device file alone (hapticemu, the sim) has no loop rate to check against.
    EXPECT_NO_THROW((void)config::loadDeviceConfig(device));
}

// The E-stop relay must sit on a bus hapticd opens (a device's), on an id no device there
// uses, and be given at least two of its 10 ms periods.
TEST(ConfigEstopRelay, TheBusMustBeADevicesAndTheIdItsOwn) {
    const auto unknown = kDataDir / "estop_unknown_bus.yaml";
    expectError(daemonError("estop_unknown_bus.yaml"),
                {unknown.string(), lineOf(unknown, "bus_device"), 15, "estop_relay.bus_device",
                 "expected the name of a device in devices ('exo', 'thimble'), got 'exoskeleton'"});
    const auto taken = kDataDir / "estop_id_of_a_device.yaml";
    expectError(daemonError("estop_id_of_a_device.yaml"),
                {taken.string(), lineOf(taken, "status_id"), 14, "estop_relay.status_id",
                 "got 0x182, a CAN id of device 'thimble'"});
    const auto fast = kDataDir / "estop_timeout_too_short.yaml";
    expectError(daemonError("estop_timeout_too_short.yaml"),
                {fast.string(), lineOf(fast, "  timeout_ms"), 15, "estop_relay.timeout_ms",
                 "expected an integer in [20, 1000], got 10"});
    const DaemonConfig relay = loadDaemonConfig(kDataDir / "estop_ok.yaml");
    EXPECT_TRUE(relay.estop_relay.enabled);
    EXPECT_EQ(relay.estop_relay.bus_device, "thimble");
    EXPECT_EQ(relay.estop_relay.status_id, 0x0E1U);
    EXPECT_EQ(relay.estop_relay.timeout_ms, 40);
    EXPECT_FALSE(loadDaemonConfig(kDataDir / "daemon_ok.yaml").estop_relay.enabled)
        << "no block: no relay";
}

// The local control socket: <socket_dir>/control-<domain>.sock, the directory absolute (the
// daemon's working directory is not the operator's); no block: /run/hapticd and 'haptic'.
TEST(ConfigControl, TheSocketDirectoryIsAbsoluteAndNamesTheSocketPerDomain) {
    const auto relative = kDataDir / "control_relative_dir.yaml";
    expectError(daemonError("control_relative_dir.yaml"),
                {relative.string(), lineOf(relative, "socket_dir"), 15, "control.socket_dir",
                 "expected an absolute directory path, got 'run/hapticd'"});
    DaemonConfig lab = loadDaemonConfig(kDataDir / "control_ok.yaml");
    EXPECT_EQ(lab.control.operator_group, "labops");
    EXPECT_EQ(controlSocketPath(lab), "/var/run/haptic-lab/control-0.sock");
    lab.dds.domain_id = 17;  // hapticctl --dds-domain 17 finds hapticd --dds-domain 17's
    EXPECT_EQ(controlSocketPath(lab), "/var/run/haptic-lab/control-17.sock");
    const DaemonConfig plain = loadDaemonConfig(kDataDir / "daemon_ok.yaml");
    EXPECT_EQ(controlSocketPath(plain), "/run/hapticd/control-0.sock");
    EXPECT_EQ(plain.control.operator_group, "haptic");
}

// Negative damping along the actuator would feed energy into the finger.
TEST(ConfigOutOfRange, NegativeActuatorDamping) {
    const auto file = kDataDir / "devices/negative_actuator_damping.yaml";
    expectError(deviceError("negative_actuator_damping.yaml"),
                {file.string(), lineOf(file, "actuator_damping_n_s_per_m"), 31,
                 "rendering.actuator_damping_n_s_per_m", "expected a number in [0, 1000], got -5"});
}

// The estimate's probe must stay well below the loop rate and within its window.
TEST(ConfigOutOfRange, UserStiffnessProbeTooFast) {
    const auto file = kDataDir / "devices/probe_too_fast.yaml";
    expectError(deviceError("probe_too_fast.yaml"),
                {file.string(), lineOf(file, "probe_frequency_hz"), 25,
                 "rendering.user_stiffness_estimate.probe_frequency_hz",
                 "expected a number in [1, 10], got 40"});
}

// The daemon's loop rate bounds the probe: its upper tone at most a twentieth of it.
TEST(ConfigOutOfRange, UserStiffnessProbeTooFastForTheLoopRate) {
    const auto device = kDataDir / "devices/exo_probe_5hz.yaml";
    expectError(daemonError("probe_at_low_rate.yaml"),
                {device.string(), lineOf(device, "probe_frequency_hz"), 25,
                 "rendering.user_stiffness_estimate.probe_frequency_hz",
                 "expected at most loop.rate_hz / 40 (3.75), got 5"});
    EXPECT_NO_THROW((void)loadDeviceConfig(device)) << "alone, no loop rate to judge it by";
}

TEST(ConfigOutOfRange, UserStiffnessProbeTooShortForItsWindow) {
    const auto file = kDataDir / "devices/probe_too_short.yaml";
    expectError(deviceError("probe_too_short.yaml"),
                {file.string(), lineOf(file, "probe_time_s"), 19,
                 "rendering.user_stiffness_estimate.probe_time_s",
                 "expected at least two periods of probe_frequency_hz (0.5 s), got 0.2"});
}

// The bit rate is the interface's: the key is refused with where to set it instead.
TEST(ConfigOutOfRange, BitrateIsNotAHapticdSetting) {
    const auto file = kDataDir / "devices/bad_bitrate.yaml";
    expectError(deviceError("bad_bitrate.yaml"),
                {file.string(), lineOf(file, "bitrate"), 12, "can.bitrate",
                 "not a hapticd setting; the bit rate is the interface's"});
}

TEST(ConfigOutOfRange, UdpPortWithoutUdpTransport) {
    const auto file = kDataDir / "devices/udp_port_without_udp_transport.yaml";
    expectError(deviceError("udp_port_without_udp_transport.yaml"),
                {file.string(), lineOf(file, "udp_port"), 13, "can.udp_port",
                 "expected can.transport: udp with this key"});
}

// The SocketCAN keys with a UDP bus would be read and do nothing: refused, like udp_port on
// SocketCAN.
TEST(ConfigOutOfRange, SocketCanKeysWithUdpTransport) {
    for (const auto& [name, key] : {std::pair{"interface_with_udp_transport.yaml", "interface"},
                                    std::pair{"fd_with_udp_transport.yaml", "fd"}}) {
        const auto file = kDataDir / "devices" / name;
        expectError(deviceError(name),
                    {file.string(), lineOf(file, std::string(key) + ":"),
                     static_cast<int>(std::string(key).size()) + 5, "can." + std::string(key),
                     "expected can.transport: socketcan with this key (a UDP bus is named by "
                     "can.udp_port), got can.transport: udp"});
    }
}

TEST(ConfigOutOfRange, UdpPortBlockPastLastPort) {
    const auto file = kDataDir / "devices/udp_port_block_past_65535.yaml";
    expectError(deviceError("udp_port_block_past_65535.yaml"),
                {file.string(), lineOf(file, "udp_port"), 13, "can.udp_port",
                 "ports ends at or below 65535, got 65530"});
}

TEST(ConfigOutOfRange, ReversedJointLimits) {
    const auto file = kDataDir / "devices/reversed_joint_limits.yaml";
    expectError(deviceError("reversed_joint_limits.yaml"),
                {file.string(), lineOf(file, "[110.0, 0.0]"), 7, "finger.joint_limits_deg[1]",
                 "with min < max, each a number in [-90, 135], got [110, 0]"});
}

TEST(ConfigOutOfRange, SafetyLimitAboveActuatorCapability) {
    const auto file = kDataDir / "devices/safety_above_actuator.yaml";
    expectError(deviceError("safety_above_actuator.yaml"),
                {file.string(), lineOf(file, "max_force_n: 50.0"), 16, "safety.max_force_n",
                 "expected a number no greater than actuator.max_force_n (40), got 50.0"});
}

TEST(ConfigOutOfRange, ThimbleLegsTooClose) {
    const auto file = kDataDir / "devices/legs_too_close.yaml";
    expectError(deviceError("legs_too_close.yaml"),
                {file.string(), lineOf(file, "leg_angles_deg"), 19, "geometry.leg_angles_deg",
                 "expected three leg angles at least 30 degrees apart, got [90, 100, 330]"});
}

TEST(ConfigNonFinite, NanIsRejected) {
    const auto file = kDataDir / "devices/nan.yaml";
    expectError(deviceError("nan.yaml"), {file.string(), lineOf(file, ".nan"), 16,
                                          "safety.max_force_n", "got .nan (not a finite number)"});
}

TEST(ConfigNonFinite, InfIsRejected) {
    const auto file = kDataDir / "devices/inf.yaml";
    expectError(deviceError("inf.yaml"),
                {file.string(), lineOf(file, ".inf"), 19, "geometry.crank_length_m",
                 "expected a number in (0, 0.1], got .inf (not a finite number)"});
}

// --- missing keys ----------------------------------------------------------------------------

TEST(ConfigMissingKeys, NestedRequiredKeyPointsAtItsMap) {
    // Line of the `loop` map (its first key), no column: the key is not there to point at.
    const auto file = kDataDir / "missing_required_key.yaml";
    const auto error = daemonError("missing_required_key.yaml");
    expectError(error, {file.string(), lineOf(file, "rate_hz"), 0, "loop.sim_timeout_ms",
                        "missing required key 'loop.sim_timeout_ms' (an integer in [1, 1000])"});
    EXPECT_EQ(std::string(error->what()),
              file.string() + ":" + std::to_string(lineOf(file, "rate_hz")) +
                  ": missing required key 'loop.sim_timeout_ms' (an integer in [1, 1000])");
}

// A misspelt key is named beside the key it stands for, not left for the operator to find.
TEST(ConfigMissingKeys, AMisspeltKeyIsNamedWithTheMissingOne) {
    const auto file = kDataDir / "misspelt_key.yaml";
    expectError(daemonError("misspelt_key.yaml"),
                {file.string(), lineOf(file, "rate_hz"), 0, "loop.sim_timeout_ms",
                 "missing required key 'loop.sim_timeout_ms' (an integer in [1, 1000]); is "
                 "'sim_timout_ms' (line " +
                     std::to_string(lineOf(file, "sim_timout_ms")) + ") a misspelling of it?"});
}

TEST(ConfigMissingKeys, DeviceSafetyLimit) {
    const auto file = kDataDir / "devices/missing_required_key.yaml";
    expectError(deviceError("missing_required_key.yaml"),
                {file.string(), lineOf(file, "max_force_n: 1.5"), 0, "safety.max_velocity_m_per_s",
                 "missing required key 'safety.max_velocity_m_per_s' (a number in (0, 5])"});
}

// A rod speed limit at or above the drive's no-load speed would never act: the drive itself
// delivers no force along the rod's motion there.
TEST(ConfigMissingKeys, AnExoskeletonVelocityLimitAboveTheDrivesSpeedIsRefused) {
    const auto file = kDataDir / "devices/exo_velocity_limit_above_drive.yaml";
    expectError(deviceError("exo_velocity_limit_above_drive.yaml"),
                {file.string(), lineOf(file, "max_velocity_m_per_s"), -1,
                 "safety.max_velocity_m_per_s", "below actuator.max_speed_m_per_s (0.08, "});
}

// A key that would have no effect is refused, not ignored: the thimble's plate is
// position-controlled, so the exoskeleton's stiffness clamp and fade-out are not its keys.
TEST(ConfigMissingKeys, AThimbleRefusesTheExoskeletonsSafetyKeys) {
    const auto file = kDataDir / "devices/thimble_with_exoskeleton_key.yaml";
    expectError(deviceError("thimble_with_exoskeleton_key.yaml"),
                {file.string(), lineOf(file, "fade_out_ms"), 16, "safety.fade_out_ms",
                 "not a thimble key"});
}

// The thimble's floor under the sim's pad model is its key only, and a floor below 1 N/m would
// guard nothing.
TEST(ConfigMissingKeys, ThePadStiffnessFloorIsTheThimblesAndAtLeast1NPerM) {
    const auto on_exo = kDataDir / "devices/pad_floor_on_exoskeleton.yaml";
    expectError(deviceError("pad_floor_on_exoskeleton.yaml"),
                {on_exo.string(), lineOf(on_exo, "min_pad_stiffness_n_per_m"), 30,
                 "safety.min_pad_stiffness_n_per_m", "not an exoskeleton key"});
    const auto too_low = kDataDir / "devices/pad_floor_too_low.yaml";
    expectError(deviceError("pad_floor_too_low.yaml"),
                {too_low.string(), lineOf(too_low, "min_pad_stiffness_n_per_m"), 30,
                 "safety.min_pad_stiffness_n_per_m", "expected a number in [1, 1e+06], got 0.5"});
}

// The optimiser's pad stiffening depth: zero would be a pad infinitely stiff at once.
TEST(ConfigMissingKeys, ThePadStiffeningDepthIsPositive) {
    const auto file = kDataDir / "devices/pad_stiffening_depth_zero.yaml";
    expectError(deviceError("pad_stiffening_depth_zero.yaml"),
                {file.string(), lineOf(file, "pad_stiffening_depth_m"), 27,
                 "optimiser.pad_stiffening_depth_m", "expected a number in (0, 0.1], got 0"});
}

TEST(ConfigMissingKeys, ReplayNeedsAFile) {
    const auto file = kDataDir / "scenes/script_keys_on_replay.yaml";
    expectError(
        sceneError("script_keys_on_replay.yaml"),
        {file.string(), lineOf(file, "source: replay"), 0, "tracking.replay_file",
         "missing required key 'tracking.replay_file' (a path to a readable file, relative to this "
         "file's directory)"});
}

// --- enums -----------------------------------------------------------------------------------

TEST(ConfigBadEnums, DaemonRealtimeMode) {
    expectError(daemonError("bad_enum.yaml"),
                {data("bad_enum.yaml"), 4, 13, "loop.realtime",
                 "loop.realtime: expected one of enforce|ignore, got the string 'sometimes'"});
}

TEST(ConfigBadEnums, RenderingMethod) {
    const auto file = kDataDir / "devices/bad_enum.yaml";
    expectError(deviceError("bad_enum.yaml"),
                {file.string(), lineOf(file, "method: magic"), 11, "rendering.method",
                 "expected one of standard|naive|nullspace|subspace|linearized_subspace|"
                 "anisotropic, got the string 'magic'"});
}

TEST(ConfigBadEnums, ShapeType) {
    const auto file = kDataDir / "scenes/bad_shape.yaml";
    expectError(sceneError("bad_shape.yaml"),
                {file.string(), lineOf(file, "shape: cone"), 12, "objects[2].shape",
                 "expected one of plane|box|sphere|capsule, got the string 'cone'"});
}

// --- lists -----------------------------------------------------------------------------------

TEST(ConfigListLengths, VectorWithTooFewItems) {
    const auto file = kDataDir / "devices/wrong_list_length.yaml";
    expectError(deviceError("wrong_list_length.yaml"),
                {file.string(), lineOf(file, "phalanx_lengths_m"), 22, "finger.phalanx_lengths_m",
                 "expected a list of 3 items, each a number in [0.005, 0.08], got a list of 2 "
                 "items"});
}

// --- names and CAN ids -----------------------------------------------------------------------

TEST(ConfigNames, DeviceNameCharacters) {
    const auto file = kDataDir / "devices/bad_name.yaml";
    expectError(deviceError("bad_name.yaml"),
                {file.string(), 1, 7, "name",
                 "expected a name of 1 to 31 characters from [a-z0-9_], got 'Exo-1'"});
}

TEST(ConfigNames, DuplicateObjectName) {
    const auto file = kDataDir / "scenes/duplicate_object.yaml";
    // The second "block" is the third object.
    int line = lineOf(file, "name: block");
    std::ifstream in(file);
    std::string text;
    for (int n = 1; std::getline(in, text); ++n) {
        if (n > line && text.find("name: block") != std::string::npos) {
            line = n;
            break;
        }
    }
    expectError(sceneError("duplicate_object.yaml"),
                {file.string(), line, 11, "objects[2].name",
                 "expected a unique object name, got 'block', already used by objects[1]"});
}

TEST(ConfigCanIds, DuplicateIdWithinDevice) {
    const auto file = kDataDir / "devices/duplicate_can_id.yaml";
    expectError(deviceError("duplicate_can_id.yaml"),
                {file.string(), lineOf(file, "state_id"), 13, "can.state_id",
                 "can.state_id: expected a CAN id different from can.command_id (0x101), got "
                 "0x101"});
}

// --- references between files ----------------------------------------------------------------

TEST(ConfigReferences, MissingDeviceFileIsReportedWhereItIsNamed) {
    const auto file = kDataDir / "missing_device_file.yaml";
    expectError(daemonError("missing_device_file.yaml"),
                {file.string(), lineOf(file, "no_such_device"), 5, "devices[1]",
                 "got 'devices/no_such_device.yaml' (" +
                     resolved(kDataDir / "devices/no_such_device.yaml") + ": " +
                     std::strerror(ENOENT) + ")"});
}

TEST(ConfigReferences, ErrorInsideDeviceFileNamesThatFile) {
    const std::string device = resolved(kDataDir / "devices/nan.yaml");
    expectError(daemonError("bad_device_file.yaml"),
                {device, lineOf(device, ".nan"), 16, "safety.max_force_n", "not a finite number"});
}

TEST(ConfigReferences, DuplicateDeviceNames) {
    const auto file = kDataDir / "duplicate_device_names.yaml";
    expectError(daemonError("duplicate_device_names.yaml"),
                {file.string(), lineOf(file, "exo_same_name"), 5, "devices[1]",
                 "expected a device with a unique name, got another device named 'exo' "
                 "(devices[0])"});
}

TEST(ConfigReferences, CanIdsSharedAcrossDevicesOnOneBus) {
    const auto file = kDataDir / "duplicate_device_ids_across_files.yaml";
    expectError(daemonError("duplicate_device_ids_across_files.yaml"),
                {file.string(), lineOf(file, "exo_renamed_copy"), 5, "devices[1]",
                 "expected a device whose CAN ids on SocketCAN can0 differ from those of 'exo' "
                 "(devices[0]), got 'exo_two' also using 0x101"});
}

// hapticd opens one bus per UDP port block (openBuses): two devices there with the same ids
// would each take the other's frames.
TEST(ConfigReferences, CanIdsSharedOnOneUdpBus) {
    const auto file = kDataDir / "duplicate_device_ids_on_one_udp_bus.yaml";
    expectError(daemonError("duplicate_device_ids_on_one_udp_bus.yaml"),
                {file.string(), lineOf(file, "exo_two_udp.yaml"), 5, "devices[1]",
                 "expected a device whose CAN ids on UDP port 47100 differ from those of 'exo' "
                 "(devices[0]), got 'exo_two' also using 0x101"});
}

TEST(ConfigReferences, OverlappingUdpPortBlocksAreRefused) {
    const auto file = kDataDir / "overlapping_udp_blocks.yaml";
    expectError(daemonError("overlapping_udp_blocks.yaml"),
                {file.string(), lineOf(file, "exo_two_udp_overlapping"), 5, "devices[1]",
                 "expected a device whose UDP port block does not overlap that of 'exo' "
                 "(devices[0], ports 47100-47107), got 'exo_two' on ports 47104-47111"});
}

TEST(ConfigReferences, TheSameCanIdsOnTwoUdpBusesAreAccepted) {
    const DaemonConfig config = loadDaemonConfig(kDataDir / "same_ids_on_two_udp_buses.yaml");
    ASSERT_EQ(config.devices.size(), 2U);
    EXPECT_EQ(config.devices[0].can.bus(), "UDP port 47100");
    EXPECT_EQ(config.devices[1].can.bus(), "UDP port 47200");
    EXPECT_EQ(config.devices[0].can.command_id, config.devices[1].can.command_id);
}

TEST(ConfigReferences, UnknownDdsParticipantProfile) {
    const auto file = kDataDir / "unknown_dds_profile.yaml";
    expectError(daemonError("unknown_dds_profile.yaml"),
                {file.string(), lineOf(file, "no_such_profile"), 24, "dds.participant_profile",
                 "(declared: test_participant), got the string 'no_such_profile'"});
}

TEST(ConfigReferences, TrackingTargetMustBeAnObject) {
    const auto file = kDataDir / "scenes/unknown_target.yaml";
    expectError(sceneError("unknown_target.yaml"),
                {file.string(), lineOf(file, "crate"), 18, "tracking.target_object",
                 "expected the name of an object in this scene, got the string 'crate'"});
}

TEST(ConfigReferences, BindingToAFingerThatIsNotSimulated) {
    const auto file = kDataDir / "scenes/wrong_finger_binding.yaml";
    expectError(sceneError("wrong_finger_binding.yaml"),
                {file.string(), lineOf(file, "finger: middle"), 21, "devices.thimble.finger",
                 "expected the simulated finger 'index' (hand.model is finger), got the string "
                 "'middle'"});
}

TEST(ConfigReferences, BindingToAFingerTheHandModelLeavesOut) {
    const auto file = kDataDir / "scenes/binding_to_missing_hand_finger.yaml";
    expectError(sceneError("binding_to_missing_hand_finger.yaml"),
                {file.string(), lineOf(file, "finger: middle"), 21, "devices.thimble.finger",
                 "expected one of the hand's fingers (hand.fingers), got the string 'middle'"});
}

TEST(ConfigReferences, HandFingerListedTwice) {
    const auto file = kDataDir / "scenes/duplicate_hand_finger.yaml";
    expectError(sceneError("duplicate_hand_finger.yaml"),
                {file.string(), lineOf(file, "fingers:"), 27, "hand.fingers[2]",
                 "expected each finger at most once, got the string 'thumb'"});
}

// handsim's key: −1 is no request, so −2 is a typo, not another way to say none.
TEST(ConfigOutOfRange, SimCpuLatencyBelowNoRequest) {
    const auto file = kDataDir / "sim_cpu_latency_out_of_range.yaml";
    expectError(
        simError("sim_cpu_latency_out_of_range.yaml"),
        {file.string(), 2, 17, "cpu_latency_us", "expected an integer in [-1, 10000], got -2"});
}

TEST(ConfigReferences, SimMissingScene) {
    const auto file = kDataDir / "sim_missing_scene.yaml";
    expectError(simError("sim_missing_scene.yaml"),
                {file.string(), 2, 8, "scene", std::strerror(ENOENT)});
}

TEST(ConfigReferences, SimDeviceNotBoundInScene) {
    const auto file = kDataDir / "sim_unbound_device.yaml";
    expectError(simError("sim_unbound_device.yaml"),
                {file.string(), lineOf(file, "exo_on_can1"), 5, "devices[1]",
                 "expected a device bound in scene 'test_scene' (bound: exo, thimble), got "
                 "'exo_two'"});
}

std::optional<ConfigError> userError(const std::string& name) {
    return configErrorOf([&] { (void)loadVirtualUserConfig(kDataDir / name); });
}

TEST(VirtualUserConfig, ReadsEveryKey) {
    const VirtualUserConfig user = loadVirtualUserConfig(kDataDir / "user_ok.yaml");
    EXPECT_EQ(user.scene.name, "test_scene");
    EXPECT_EQ(user.hand_impedance.stiffness_nm_per_rad[1], 0.5);
    EXPECT_EQ(user.hand_impedance.inertia_kg_m2[0], 4.5e-5);
    EXPECT_EQ(user.hand_impedance.damping_nms_per_rad[2], 0.002);
    EXPECT_EQ(user.pad.radius_m, 0.0075);
    EXPECT_EQ(user.pad.effective_modulus_pa, 8.0e4);
    EXPECT_EQ(user.tracker.topic, "tracking/hand");  // the default
    EXPECT_EQ(user.tracker.rate_hz, 60);
    EXPECT_EQ(user.tracker.latency_ms, 35.0);
    EXPECT_EQ(user.tracker.position_noise_m, 0.0005);
    EXPECT_EQ(user.tracker.angle_noise_rad, 0.0);
    EXPECT_EQ(user.dds.domain_id, 7);
    ASSERT_EQ(user.devices.size(), 2U);
    EXPECT_EQ(user.devices[1].name, "thimble");
}

TEST(VirtualUserConfig, TheIntentNeedsAScriptOrAReplayNotATopic) {
    const auto file = kDataDir / "user_topic_scene.yaml";
    expectError(userError("user_topic_scene.yaml"),
                {file.string(), lineOf(file, "scene:"), 8, "scene",
                 "expected a scene whose tracking source is scripted or replay"});
}

TEST(VirtualUserConfig, AllWornDevicesShareOneBus) {
    const auto file = kDataDir / "user_two_buses.yaml";
    expectError(userError("user_two_buses.yaml"),
                {file.string(), lineOf(file, "thimble_on_can1"), 5, "devices[1]",
                 "got 'thimble' on another bus"});
}

TEST(VirtualUserConfig, AJointWithoutStiffnessIsRefused) {
    const auto file = kDataDir / "user_zero_stiffness.yaml";
    expectError(userError("user_zero_stiffness.yaml"),
                {file.string(), lineOf(file, "stiffness_nm_per_rad"), -1,
                 "hand_impedance.stiffness_nm_per_rad[1]", "got 0"});
}

// Without a pad block the user's pad is the documented default (the scene's fingertip and
// the FEM tissue's material).
TEST(VirtualUserConfig, WithoutAPadBlockThePadIsTheDefault) {
    const VirtualUserConfig user = loadVirtualUserConfig(kDataDir / "user_default_pad.yaml");
    EXPECT_EQ(user.pad.radius_m, 0.008);
    EXPECT_EQ(user.pad.effective_modulus_pa, 6.27e4);
}

TEST(VirtualUserConfig, APadRadiusInTheWrongUnitIsRefused) {
    const auto file = kDataDir / "user_pad_radius.yaml";
    expectError(userError("user_pad_radius.yaml"),
                {file.string(), lineOf(file, "radius_m"), -1, "pad.radius_m", "got 0.08"});
}

TEST(ConfigReferences, ExoskeletonNeedsFingerJoints) {
    const auto file = kDataDir / "sim_exoskeleton_on_fingertip.yaml";
    expectError(simError("sim_exoskeleton_on_fingertip.yaml"),
                {file.string(), lineOf(file, "exo_ok"), 5, "devices[0]",
                 "got exoskeleton 'exo' with hand.model fingertip (no joints)"});
}

// The coupling keys are optional; set, they replace the defaults (their effect on the
// rendering: DeviceRuntime.EveryCouplingKeyOfTheDeviceFileChangesTheRendering).
TEST(ConfigCoupling, KeysReplaceTheDefaults) {
    const auto exo = loadDeviceConfig(kDataDir / "devices/exo_coupling.yaml").exoskeleton();
    EXPECT_DOUBLE_EQ(exo.rendering.tracking_stiffness_nm_per_rad, 3.5);
    EXPECT_DOUBLE_EQ(exo.rendering.user_stiffness_nm_per_rad, 0.9);
    EXPECT_DOUBLE_EQ(exo.rendering.actuator_damping_n_s_per_m, 12.5);
    EXPECT_DOUBLE_EQ(exo.rendering.passivity_port_mass_kg, 0.25);
    EXPECT_TRUE(exo.rendering.user_stiffness_estimate.enabled);
    EXPECT_DOUBLE_EQ(exo.rendering.user_stiffness_estimate.probe_amplitude_m, 30e-6);
    EXPECT_DOUBLE_EQ(exo.rendering.user_stiffness_estimate.probe_frequency_hz, 4.0);
    EXPECT_DOUBLE_EQ(exo.rendering.user_stiffness_estimate.probe_time_s, 3.0);
    const auto defaults = loadDeviceConfig(kDataDir / "devices/exo_ok.yaml").exoskeleton();
    EXPECT_DOUBLE_EQ(defaults.rendering.tracking_stiffness_nm_per_rad, 2.0);
    EXPECT_DOUBLE_EQ(defaults.rendering.passivity_port_mass_kg, 0.1);
    EXPECT_FALSE(defaults.rendering.user_stiffness_estimate.enabled);
}

}  // namespace
}  // namespace haptic::config
