#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "closed_loop_report.hpp"
#include "haptic/msgs/names.hpp"
#include "status_format.hpp"
#include "status_json.hpp"
#include "telemetry_csv.hpp"

namespace haptic::ctl {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

TEST(SimStatusFormat, ShowsRateStepTimeZeroedStepsAndTheLastRejectedInput) {
    msgs::SimStatus status;
    status.header.seq = 42;
    status.header.source_id.assign("thimble_only");
    status.model.assign("softhand_fingertip_index_res1");
    status.node_count = 169;
    status.element_count = 516;
    status.steps = 4000;
    status.rate_hz = 200.0;
    status.step_time_us = {511.0, 1286.0, 2543.0};
    status.solver_iterations = 30;
    status.solver_residual = 1.5e-4;
    status.energy_j = 2.5e-3;
    status.steps_rescaled = 220;
    status.steps_substepped = 0;
    status.steps_zeroed = 4;
    const std::string clean = formatSimStatus(status, 0.2);
    EXPECT_THAT(clean, HasSubstr("scene 'thimble_only'"));
    EXPECT_THAT(clean, HasSubstr("softhand_fingertip_index_res1 (169 nodes, 516 elements)"));
    EXPECT_THAT(clean, HasSubstr("4000 at 200.0 Hz"));
    EXPECT_THAT(clean, HasSubstr("p50   511.0 us"));
    EXPECT_THAT(clean,
                HasSubstr("220 steps rescaled (5.5%), 0 substepped (0.0%), 4 frozen (0.1%)"));
    EXPECT_THAT(clean, HasSubstr("no input rejected"));

    status.inputs_rejected = 3;
    status.last_rejection.assign("hand pose: position is not finite");
    const std::string rejected = formatSimStatus(status, -1.0);
    EXPECT_THAT(rejected, HasSubstr("3 inputs rejected, last: hand pose: position is not finite"));
    EXPECT_THAT(rejected, Not(HasSubstr("s old")));
}

TEST(StatusFormat, ShowsStateLoopSimLinkDevicesAndFaults) {
    msgs::HapticStatus status;
    status.state = msgs::DaemonState::kIdle;
    status.rendering_method.assign("subspace");
    status.uptime_s = 12.5;
    status.loop.rate_hz = 1000;
    status.loop.ticks = 12500;
    status.loop.overruns = 3;
    status.loop.overruns_compute = 2;
    status.loop.overruns_write = 1;
    status.loop.wakeup_latency_us = {11.0, 52.0, 700.0};
    status.sim_link.connected = true;
    status.sim_link.age_ms = 4.5;
    status.sim_link.rate_hz = 99.8;
    msgs::DeviceStatus device;
    device.device_id.assign("exo_index");
    device.kind = msgs::DeviceKind::kExoskeleton;
    device.can.bus_state = msgs::BusState::kBusOff;
    device.last_frame_age_ms = -1.0;
    status.devices.push_back(device);
    msgs::Fault fault;
    fault.code = 7;
    fault.device_id.assign("exo_index");
    fault.message.assign("heartbeat missing for 50 ms");
    status.faults.push_back(fault);

    EXPECT_THAT(formatStatus(status, 0.05),
                HasSubstr("Version: hapticd (unknown)   configuration (unknown)"));
    status.version.assign("1.2.3");
    status.config_digest.assign(
        "sha256:0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef");
    const std::string text = formatStatus(status, 0.05);
    EXPECT_THAT(text, HasSubstr("Version: hapticd 1.2.3   configuration sha256:0123456789ab\n"));
    EXPECT_THAT(text, HasSubstr("State: IDLE"));
    EXPECT_THAT(text, HasSubstr("Uptime: 12.5 s   (status #0, 0.05 s old)"));
    EXPECT_THAT(text, HasSubstr("rendering method: subspace"));
    EXPECT_THAT(text, HasSubstr("1000 Hz, 12500 ticks, 3 overruns (read 0 / compute 2 / write 1)"));
    EXPECT_THAT(text, HasSubstr("wake-up   p50    11.0 us   p99    52.0 us   max   700.0 us"));
    EXPECT_THAT(text, HasSubstr("iceoryx, connected, last input 4.5 ms ago, 99.8 Hz"));
    EXPECT_THAT(text, HasSubstr("exo_index"));
    EXPECT_THAT(text, HasSubstr("bus-off"));
    EXPECT_THAT(text, HasSubstr("last frame never"));
    EXPECT_THAT(text, HasSubstr("[7] exo_index: heartbeat missing for 50 ms"));
}

// `hapticctl status --json`: the same snapshot, every field of the screen, with the schema's
// names; unknown ages are null, not -1.
TEST(StatusJson, CarriesEveryFieldOfTheScreenUnderTheDocumentedNames) {
    msgs::HapticStatus status;
    status.header.seq = 42;
    status.state = msgs::DaemonState::kFault;
    status.rendering_method.assign("anisotropic");
    status.version.assign("1.2.3");
    status.config_digest.assign("sha256:00ff");
    status.uptime_s = 12.5;
    status.loop.rate_hz = 1000;
    status.loop.ticks = 12500;
    status.loop.overruns = 3;
    status.loop.overruns_compute = 2;
    status.loop.wakeup_latency_us = {11.0, 52.0, 700.0};
    status.sim_link.transport = msgs::SimTransport::kDds;
    status.sim_link.age_ms = -1.0;
    status.sim_link.received = 7;
    status.sim_link.rejected = 3;
    status.sim_link.rejected_by_reason[msgs::reasonIndex(msgs::SimInputRejection::kNotNewer)] = 2;
    status.sim_link.rejected_by_reason[msgs::reasonIndex(msgs::SimInputRejection::kStampAhead)] = 1;
    msgs::DeviceStatus device;
    device.device_id.assign("exo");
    device.kind = msgs::DeviceKind::kExoskeleton;
    device.state = msgs::DeviceRunState::kFault;
    device.awaiting_enable = true;
    device.can.bus_state = msgs::BusState::kBusOff;
    device.can.rx_frames = 123;
    device.last_frame_age_ms = 0.5;
    status.devices.push_back(device);
    msgs::Fault fault;
    fault.code = 102;
    fault.device_id.assign("exo");
    fault.message.assign("device reports fault 2 (overtemperature); \"held\" safe");
    status.faults.push_back(fault);

    const auto json = nlohmann::json::parse(statusJson(status, -1.0));
    EXPECT_EQ(json["schema"], "haptic.status/1");
    EXPECT_EQ(json["hapticctl_version"], HAPTIC_VERSION);
    EXPECT_EQ(json["seq"], 42);
    EXPECT_TRUE(json["age_s"].is_null());
    EXPECT_EQ(json["state"], "FAULT");
    EXPECT_EQ(json["rendering_method"], "anisotropic");
    EXPECT_EQ(json["version"], "1.2.3");
    EXPECT_EQ(json["config_digest"], "sha256:00ff");
    EXPECT_EQ(json["uptime_s"], 12.5);
    EXPECT_EQ(json["loop"]["ticks"], 12500);
    EXPECT_EQ(json["loop"]["overruns_compute"], 2);
    EXPECT_EQ(json["loop"]["wakeup_latency_us"]["p99"], 52.0);
    EXPECT_EQ(json["sim_link"]["transport"], msgs::toString(msgs::SimTransport::kDds));
    EXPECT_TRUE(json["sim_link"]["age_ms"].is_null());
    EXPECT_EQ(json["sim_link"]["rejected"], 3);
    // Every reason, by its key, also those that never happened.
    ASSERT_EQ(json["sim_link"]["rejected_by_reason"].size(), msgs::kSimInputRejectionReasons);
    EXPECT_EQ(json["sim_link"]["rejected_by_reason"]["not_newer"], 2);
    EXPECT_EQ(json["sim_link"]["rejected_by_reason"]["non_finite"], 0);
    EXPECT_EQ(json["sim_link"]["rejected_by_reason"]["stamp_ahead"], 1);
    ASSERT_EQ(json["devices"].size(), 1U);
    EXPECT_EQ(json["devices"][0]["id"], "exo");
    EXPECT_EQ(json["devices"][0]["kind"], "exoskeleton");
    EXPECT_EQ(json["devices"][0]["state"], msgs::toString(msgs::DeviceRunState::kFault));
    EXPECT_EQ(json["devices"][0]["awaiting_enable"], true);
    EXPECT_EQ(json["devices"][0]["last_frame_age_ms"], 0.5);
    EXPECT_EQ(json["devices"][0]["can"]["bus_state"], "bus-off");
    EXPECT_EQ(json["devices"][0]["can"]["rx_frames"], 123);
    ASSERT_EQ(json["faults"].size(), 1U);
    EXPECT_EQ(json["faults"][0]["code"], 102);
    EXPECT_EQ(json["faults"][0]["device"], "exo");
    EXPECT_EQ(json["faults"][0]["message"], std::string(fault.message.view()));
    EXPECT_EQ(nlohmann::json::parse(statusJson(status, 0.25))["age_s"], 0.25);
}

TEST(StatusJson, HandsimsStatusToo) {
    msgs::SimStatus status;
    status.header.source_id.assign("default");
    status.model.assign("softhand_finger_index_res1");
    status.steps = 900;
    status.steps_zeroed = 12;
    status.steps_rescaled = 7;
    status.step_time_us = {4000.0, 9000.0, 12000.0};
    status.last_rejection.assign("HandPose on 'tracking/hand': wrist_position_m is not finite");
    const auto json = nlohmann::json::parse(simStatusJson(status, 0.1));
    EXPECT_EQ(json["schema"], "haptic.sim_status/1");
    EXPECT_EQ(json["scene"], "default");
    EXPECT_EQ(json["model"], "softhand_finger_index_res1");
    EXPECT_EQ(json["steps"], 900);
    EXPECT_EQ(json["steps_zeroed"], 12);
    EXPECT_EQ(json["steps_rescaled"], 7);
    EXPECT_EQ(json["step_time_us"]["p99"], 9000.0);
    EXPECT_EQ(json["last_rejection"], std::string(status.last_rejection.view()));
}

// Text from the daemon or the sim is not checked UTF-8 (a device id from YAML, a message cut
// at its capacity mid-character): the JSON stays valid, the bad bytes become U+FFFD.
TEST(StatusJson, TextThatIsNotUtf8StaysValidJson) {
    msgs::HapticStatus status;
    msgs::Fault fault;
    fault.code = 100;
    fault.device_id.assign("exo\xff");
    fault.message.assign("heartbeat lost \xc3");  // the first byte of a two-byte character
    status.faults.push_back(fault);
    nlohmann::json json;
    ASSERT_NO_THROW(json = nlohmann::json::parse(statusJson(status, 0.0)));
    EXPECT_EQ(json["faults"][0]["device"], "exo\xef\xbf\xbd");
    EXPECT_EQ(json["faults"][0]["message"], "heartbeat lost \xef\xbf\xbd");
    msgs::SimStatus sim;
    sim.last_rejection.assign("bad \xfe pose");
    ASSERT_NO_THROW(json = nlohmann::json::parse(simStatusJson(sim, 0.0)));
    EXPECT_EQ(json["last_rejection"], "bad \xef\xbf\xbd pose");
}

TEST(StatusFormat, ADeviceAwaitingEnableSaysWhyAndHowToReArm) {
    msgs::HapticStatus status;
    msgs::DeviceStatus device;
    device.device_id.assign("exo");
    status.devices.push_back(device);
    EXPECT_THAT(formatStatus(status, 0.05), Not(HasSubstr("AWAITING ENABLE")));
    status.devices[0].awaiting_enable = true;
    EXPECT_THAT(formatStatus(status, 0.05),
                HasSubstr("AWAITING ENABLE: its sim input was lost longer than "
                          "loop.sim_rearm_after_ms; `hapticctl enable` re-arms it"));
}

TEST(StatusFormat, LateSimInputIsShownOnlyWhenItHappened) {
    msgs::HapticStatus status;
    status.sim_link.connected = true;
    EXPECT_THAT(formatStatus(status, 0.05), Not(HasSubstr("late input")));
    status.sim_link.late_input_ticks = 1234;
    EXPECT_THAT(formatStatus(status, 0.05),
                HasSubstr("late input faded the force on 1234 ticks (sim slower than 3/4 of "
                          "sim_timeout_ms, or stalled)"));
}

// The operator sees which check refused the sim's messages: a NaN from the sim is not a late
// message on a loaded machine.
TEST(StatusFormat, RejectedSimInputIsShownByReasonOnlyWhenItHappened) {
    msgs::HapticStatus status;
    status.sim_link.connected = true;
    EXPECT_THAT(formatStatus(status, 0.05), Not(HasSubstr("rejected:")));
    // A status from a hapticd that does not count them by reason says so.
    status.sim_link.rejected = 7;
    EXPECT_THAT(formatStatus(status, 0.05),
                HasSubstr("7 rejected\n            rejected: by reason unknown"));
    status.sim_link.rejected_by_reason[msgs::reasonIndex(msgs::SimInputRejection::kNonFinite)] = 1;
    status.sim_link.rejected_by_reason[msgs::reasonIndex(msgs::SimInputRejection::kDelayed)] = 4;
    status.sim_link.rejected_by_reason[msgs::reasonIndex(msgs::SimInputRejection::kStampAhead)] = 2;
    EXPECT_THAT(
        formatStatus(status, 0.05),
        HasSubstr("7 rejected\n            rejected: non_finite 1, delayed 4, stamp_ahead 2\n"));
}

TEST(StatusFormat, SaysWhenTheSimIsNotConnected) {
    msgs::HapticStatus status;
    status.sim_link.age_ms = -1.0;
    const std::string text = formatStatus(status, -1.0);
    EXPECT_THAT(text, Not(HasSubstr(" old)"))) << "an unknown age is not shown";
    EXPECT_THAT(text, HasSubstr("NOT CONNECTED, last input never"));
    EXPECT_THAT(text, HasSubstr("Faults: none"));
}

}  // namespace
}  // namespace haptic::ctl

namespace haptic::ctl {
namespace {

TEST(TelemetryCsv, OneRowPerSampleWithTimeFromTheOriginAndEveryActuator) {
    msgs::TelemetrySample sample;
    sample.tick = 1234;
    sample.stamp_ns = 3'500'000'000;
    sample.device_index = 1;
    sample.device_kind = msgs::DeviceKind::kThimble;
    sample.exoskeleton.actuator_force_cmd_n = 2.0;
    sample.thimble.servo_angle_cmd_rad = {1.5, -0.25, 0.0};
    sample.thimble.reference_force_device_n = {0.25, 0.0, -1.0};
    sample.thimble.reference_moment_device_nm = {0.0, 0.001, 0.0};
    sample.thimble.pad_force_model_n = 0.75;
    sample.thimble.pad_limit_flags = 3;
    sample.tick_work_us = 7.3;
    sample.wakeup_latency_us = 55.5;
    sample.read_us = 3.25;
    sample.write_us = 2.5;
    EXPECT_EQ(telemetryCsvHeader(),
              "tick,time_s,device,device_kind,actuator_force_cmd_n,servo_angle_cmd_0_rad,"
              "servo_angle_cmd_1_rad,servo_angle_cmd_2_rad,"
              "tick_work_us,wakeup_latency_us,read_us,write_us,"
              "exo_joint_0_rad,exo_joint_1_rad,exo_joint_2_rad,"
              "exo_proxy_0_rad,exo_proxy_1_rad,exo_proxy_2_rad,exo_actuator_force_n,"
              "exo_reference_torque_0_nm,exo_reference_torque_1_nm,exo_reference_torque_2_nm,"
              "exo_reference_actuator_force_n,"
              "exo_ghost_torque_0_nm,exo_ghost_torque_1_nm,exo_ghost_torque_2_nm,"
              "exo_energy_observer_j,exo_environment_work_j,servo_angle_0_rad,servo_angle_1_rad,"
              "servo_angle_2_rad,"
              "thimble_reference_force_x_n,thimble_reference_force_y_n,"
              "thimble_reference_force_z_n,thimble_reference_moment_x_nm,"
              "thimble_reference_moment_y_nm,thimble_reference_moment_z_nm,"
              "thimble_pad_force_model_n,thimble_pad_limit_flags,"
              "tracking_sampled_s,tracking_received_s\n");
    const std::string row =
        "1234,2.500000,1,thimble,2.0000,1.5000,-0.2500,0.0000,7.30,55.50,3.25,2.50,"
        "0.000000,0.000000,0.000000,0.000000,0.000000,0.000000,0.0000,"
        "0.000000,0.000000,0.000000,0.0000,0.000000,0.000000,0.000000,0.000000000,"
        "0.000000000,0.0000,0.0000,0.0000,0.2500,0.0000,-1.0000,0.000000,0.001000,0.000000,"
        "0.7500,3";
    EXPECT_EQ(telemetryCsvRow(sample, 1'000'000'000), row + ",,\n") << "a scripted hand";
    sample.tracking = {3'460'000'000, 3'481'500'000};
    EXPECT_EQ(telemetryCsvRow(sample, 1'000'000'000), row + ",2.460000,2.481500\n");
}

// A recording says who made it, when, from which hapticd and configuration, and which device
// each index is; the readers skip those lines.
TEST(TelemetryCsv, TheProvenanceLinesNameTheRecordingAndReadersSkipThem) {
    msgs::HapticStatus status;
    status.version.assign("0.1.0");
    status.config_digest.assign("sha256:00aa");
    msgs::DeviceStatus exo;
    exo.device_id.assign("exo");
    exo.kind = msgs::DeviceKind::kExoskeleton;
    msgs::DeviceStatus thimble;
    thimble.device_id.assign("thimble");
    thimble.kind = msgs::DeviceKind::kThimble;
    ASSERT_TRUE(status.devices.push_back(exo));
    ASSERT_TRUE(status.devices.push_back(thimble));
    // 2026-11-27 07:55:12 UTC
    const std::int64_t wall_clock_ns = 1'795'766'112LL * 1'000'000'000 + 250'000'000;
    const std::string provenance =
        telemetryCsvProvenance("0.1.0", wall_clock_ns, 123'456'789'000, &status);
    EXPECT_EQ(provenance,
              "# hapticctl record 0.1.0\n"
              "# started 2026-11-27T07:55:12Z (first sample, wall clock)\n"
              "# time_s 0 is CLOCK_MONOTONIC ns 123456789000 (hapticd's stamp of the first "
              "sample)\n"
              "# hapticd 0.1.0, configuration sha256:00aa\n"
              "# devices: 0 exo (exoskeleton), 1 thimble (thimble)\n");
    const RecordingInfo info = readRecordingInfo(provenance + telemetryCsvHeader());
    EXPECT_EQ(info.origin_ns, 123'456'789'000);
    EXPECT_EQ(info.device_names, (std::map<int, std::string>{{0, "exo"}, {1, "thimble"}}));
    EXPECT_THAT(telemetryCsvProvenance("0.1.0", wall_clock_ns, 0, nullptr),
                HasSubstr("# hapticd: no status received, version and configuration unknown\n"));

    msgs::TelemetrySample sample;
    sample.device_index = 1;
    sample.device_kind = msgs::DeviceKind::kThimble;
    sample.tick = 7;
    const auto devices =
        readTelemetryCsv(provenance + telemetryCsvHeader() + telemetryCsvRow(sample, 0));
    ASSERT_EQ(devices.size(), 1U);
    EXPECT_EQ(devices.at(1).kind, "thimble");
    EXPECT_EQ(devices.at(1).column("tick").front(), 7.0);
}

// Every 10th tick sent: per device, a step of 30 is two samples missing.
TEST(TelemetryCsv, GapsInEachDevicesTickNumbersCountAsMissingSamples) {
    TickGapCounter gaps(10);
    for (const std::uint64_t tick : {100U, 110U, 120U}) {
        gaps.add(0, tick);
        gaps.add(1, tick);
    }
    EXPECT_EQ(gaps.missing(), 0U);
    gaps.add(0, 150);  // 130 and 140 missing
    gaps.add(1, 130);
    EXPECT_EQ(gaps.missing(), 2U);
}

// The felt pad force comes from the felt log, on the recording's time axis: its stamps less
// the recording's origin. Columns 5-7 are force_x_n..force_z_n, the header readFeltLog checks.
TEST(TelemetryCsv, PlotScriptPutsTheFeltLogOnTheRecordingsTimeAxis) {
    const FeltLogPlot felt{"/tmp/felt.csv", 7'000'000'000'123, 12.5, 3456, {"left", "right"}};
    const auto script = telemetryPlotScript("t.csv", "t.png", 10.0, 1.5, &felt);
    for (const std::string device : {"left", "right"}) {
        // One line per device, only its rows with a known pose, over the recording's span.
        EXPECT_THAT(script,
                    HasSubstr("'/tmp/felt.csv' every ::1::3456 using (strcol(2) eq '" + device +
                              "' && $4 == 1 && $1 >= 7000000000123 && ($1 - "
                              "7000000000123) * 1e-9 <= 12.5 ? ($1 - 7000000000123) * "
                              "1e-9 : 1/0):(sqrt($6**2 + $7**2 + $8**2)) axes x1y2"));
    }
    EXPECT_THAT(telemetryPlotScript("t.csv", "t.png"), Not(HasSubstr("felt pad force")));
    // A log with no complete row yet plots nothing from it (every ::1::0 would be an error).
    const FeltLogPlot empty{"/tmp/felt.csv", 1, 12.5, 0, {"left"}};
    EXPECT_THAT(telemetryPlotScript("t.csv", "t.png", 10.0, 1.5, &empty),
                Not(HasSubstr("felt pad force")));
}

TEST(TelemetryCsv, PlotScriptQuotesPathsForGnuplot) {
    const auto script = telemetryPlotScript("/tmp/it's.csv", "/tmp/out.png");
    EXPECT_NE(script.find("set output '/tmp/out.png'"), std::string::npos) << script;
    EXPECT_NE(script.find("plot '/tmp/it''s.csv'"), std::string::npos) << script;
}

// The plot addresses columns by number; they must be the named ones, whatever was added.
TEST(TelemetryCsv, PlotScriptPlotsTheNamedColumns) {
    const std::string header = telemetryCsvHeader();
    std::vector<std::string> names;
    std::stringstream stream(header.substr(0, header.find('\n')));
    for (std::string name; std::getline(stream, name, ',');) {
        names.push_back(name);
    }
    auto number = [&names](const std::string& name) {
        const auto it = std::find(names.begin(), names.end(), name);
        EXPECT_NE(it, names.end()) << name;
        return std::to_string(it - names.begin() + 1);
    };
    const auto script = telemetryPlotScript("t.csv", "t.png");
    EXPECT_NE(script.find("(sqrt($" + number("thimble_reference_force_x_n") + "**2 + $" +
                          number("thimble_reference_force_y_n") + "**2 + $" +
                          number("thimble_reference_force_z_n") + "**2))"),
              std::string::npos)
        << script;
    for (const char* name : {"exo_reference_actuator_force_n", "actuator_force_cmd_n",
                             "exo_actuator_force_n", "servo_angle_cmd_2_rad"}) {
        EXPECT_NE(script.find("? $2 : 1/0):" + number(name) + " with"), std::string::npos)
            << name << "\n"
            << script;
    }
    EXPECT_NE(script.find("? $2 : 1/0):" + number("thimble_pad_force_model_n") + " axes x1y2"),
              std::string::npos)
        << script;
}

}  // namespace
}  // namespace haptic::ctl
