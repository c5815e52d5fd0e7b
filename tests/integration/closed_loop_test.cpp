// The closed loop as the demo runs it, with the real parts: iox-roudi with config/roudi.toml,
// Fast DDS on a test-only domain, `hapticemu --user` (the virtual user wearing both devices on
// the UDP bus and publishing its hand on tracking/hand), hapticd, and handsim tracking that
// topic, all with the shipped configuration. One recorded run is judged by what the finger
// gets (closed_loop_report.hpp): force only in contact, no clamp, a passive port, the thimble
// pressing only in contact, and live method switches while rendering. And a tracker that stops
// during contact: the force is gone within the tracking timeout plus sim_timeout_ms.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "bus_listener.hpp"
#include "child_process.hpp"
#include "closed_loop_report.hpp"
#include "emulator_process.hpp"
#include "haptic/config/daemon.hpp"
#include "haptic/config/sim.hpp"
#include "haptic/ipc/iceoryx_runtime.hpp"
#include "loop_stall_retry.hpp"

namespace haptic::testing {
namespace {

using namespace std::chrono_literals;

const std::string kConfigDir = HAPTIC_CONFIG_DIR;

std::string domainArgument() {
    return std::to_string(100 + (::getpid() + 50) % 100);
}

CommandResult ctl(std::vector<std::string> arguments) {
    arguments.insert(arguments.begin(), {HAPTICCTL_PATH, "--dds-domain", domainArgument()});
    return runCommand(arguments, 30s);
}

// Ticks on which `reference` stays below `threshold` for `settle` ticks before and after:
// clear of contact. (At an onset hapticd renders before the sim's reference shows the contact:
// the device's finger is where the tracker will see it one latency later, and the daemon
// re-solves the sim's linearised constraints against it at 1 kHz.)
std::vector<bool> settledWithout(const std::vector<double>& reference, double threshold,
                                 std::size_t settle) {
    const std::size_t n = reference.size();
    std::vector<std::size_t> quiet_before(n, 0), quiet_after(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const bool quiet = std::abs(reference[i]) < threshold;
        quiet_before[i] = quiet ? (i > 0 ? quiet_before[i - 1] : 0) + 1 : 0;
    }
    for (std::size_t i = n; i-- > 0;) {
        const bool quiet = std::abs(reference[i]) < threshold;
        quiet_after[i] = quiet ? (i + 1 < n ? quiet_after[i + 1] : 0) + 1 : 0;
    }
    std::vector<bool> out(n, false);
    for (std::size_t i = 0; i < n; ++i) {
        out[i] = quiet_before[i] > settle && quiet_after[i] > settle;
    }
    return out;
}

// The closed loop of the demo, up and enabled: iox-roudi, the virtual user (hapticemu --user,
// at FIFO 70 below hapticd's 80, as the devices' firmware and the user's hand), hapticd and
// handsim tracking the user's topic. Under the sanitizers handsim steps at ~4 Hz, so hapticd
// fades every sim input as stale and no contact is rendered to judge: skipped there.
class ClosedLoop : public ::testing::Test {
  protected:
    void SetUp() override {
        if (HAPTIC_SANITIZED != 0) {
            GTEST_SKIP() << "under the sanitizers handsim steps at ~4 Hz: no contact to judge";
        }
        ASSERT_FALSE(ipc::probeRoudi().reachable) << "an iox-roudi is already running; stop it";
        roudi_ = std::make_unique<ChildProcess>(
            std::vector<std::string>{IOX_ROUDI_EXECUTABLE, "-c", kConfigDir + "/roudi.toml", "-l",
                                     "warning"},
            "roudi");
        for (auto deadline = std::chrono::steady_clock::now() + 10s;
             !ipc::probeRoudi().reachable;) {
            ASSERT_TRUE(roudi_->running()) << roudi_->stderrText();
            ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "iox-roudi did not come up";
            std::this_thread::sleep_for(20ms);
        }
        user_ = std::make_unique<EmulatorProcess>(
            withFifoPriority({HAPTICEMU_PATH, "--user", kConfigDir + "/user.yaml", "--dds-domain",
                              domainArgument(), "--felt-log", felt_log_},
                             70));
        daemon_ = std::make_unique<ChildProcess>(
            std::vector<std::string>{HAPTICD_PATH, "--realtime", "ignore", "--dds-domain",
                                     domainArgument()},
            "hapticd");
        sim_ = std::make_unique<ChildProcess>(
            std::vector<std::string>{HANDSIM_PATH, "--dds-domain", domainArgument(),
                                     "--tracking-topic", "tracking/hand"},
            "handsim");
        // hapticd accepts enable once both devices report in.
        CommandResult enabled;
        for (auto deadline = std::chrono::steady_clock::now() + 30s;
             std::chrono::steady_clock::now() < deadline;) {
            ASSERT_TRUE(user_->running()) << user_->output();
            ASSERT_TRUE(daemon_->running()) << daemon_->stderrText();
            ASSERT_TRUE(sim_->running()) << sim_->stderrText();
            enabled = ctl({"enable"});
            if (enabled.exit_code == 0) {
                break;
            }
            std::this_thread::sleep_for(500ms);
        }
        ASSERT_EQ(enabled.exit_code, 0) << enabled.err;
    }

    void TearDown() override {
        if (HasFailure() && daemon_) {
            noteFailureAfterLoopStall(daemon_->stderrText(), daemon_->running());
        }
        for (auto* process : {sim_.get(), daemon_.get()}) {
            if (process != nullptr) {
                EXPECT_EQ(process->terminate(), std::optional<int>(0)) << process->stderrText();
            }
        }
        if (user_) {
            EXPECT_EQ(user_->stop(), 0) << user_->output();
        }
        if (roudi_) {
            EXPECT_EQ(roudi_->terminate(), std::optional<int>(0));
        }
        std::filesystem::remove(felt_log_);
    }

    // What the user's pad under the thimble felt, every tick (hapticemu --felt-log).
    const std::string felt_log_ =
        "/tmp/haptic-closed-loop-felt-" + std::to_string(::getpid()) + ".csv";

    std::unique_ptr<ChildProcess> roudi_;
    std::unique_ptr<EmulatorProcess> user_;
    std::unique_ptr<ChildProcess> daemon_;
    std::unique_ptr<ChildProcess> sim_;
};

TEST_F(ClosedLoop, TheLoopClosesWithForceOnlyInContactNoClampAndLiveMethodSwitches) {
    // Two periods of the default scene's script (6 s each), with every method switched in
    // live during the second.
    const std::string csv = "/tmp/haptic-closed-loop-" + std::to_string(::getpid()) + ".csv";
    // Up to 10 s for the first telemetry (not the default 2 s): beside CPU-heavy tests the new
    // participant's discovery took longer and record gave up with "no daemon" (exit 3).
    ChildProcess recorder({HAPTICCTL_PATH, "--dds-domain", domainArgument(), "--timeout", "10",
                           "record", csv, "--duration", "12"},
                          "record");
    std::this_thread::sleep_for(6s);
    for (const char* method :
         {"naive", "subspace", "anisotropic", "nullspace", "standard", "linearized_subspace"}) {
        const CommandResult switched = ctl({"method", method});
        EXPECT_EQ(switched.exit_code, 0) << method << ": " << switched.err;
        std::this_thread::sleep_for(300ms);
    }
    ASSERT_EQ(recorder.waitFor(40s), std::optional<int>(0)) << recorder.stderrText();
    const CommandResult status = ctl({"status", "--timeout", "5"});
    EXPECT_THAT(status.out, ::testing::HasSubstr("State: RENDERING")) << status.err;
    EXPECT_THAT(status.out, ::testing::HasSubstr("Faults: none")) << status.out;

    std::ifstream file(csv);
    std::stringstream text;
    text << file.rdbuf();
    // The recording names its source: this hapticd's version and configuration digest, as
    // its status shows them, and the device of each index.
    const std::string provenance = text.str().substr(0, text.str().find("\ntick,"));
    EXPECT_THAT(provenance, ::testing::StartsWith("# hapticctl record "));
    EXPECT_THAT(provenance,
                ::testing::ContainsRegex("# hapticd [0-9.]+, configuration sha256:[0-9a-f]{64}\n"));
    EXPECT_THAT(provenance,
                ::testing::HasSubstr("# devices: 0 exo (exoskeleton), 1 thimble (thimble)"));
    EXPECT_THAT(status.out, ::testing::HasSubstr("   Version: hapticd " HAPTIC_VERSION
                                                 "   configuration sha256:"));
    const auto devices = ctl::readTelemetryCsv(text.str());
    std::filesystem::remove(csv);
    ASSERT_EQ(devices.size(), 2U);
    const ctl::DeviceColumns& exo = devices.at(0);
    const ctl::DeviceColumns& thimble = devices.at(1);
    ASSERT_EQ(exo.kind, "exoskeleton");
    ASSERT_GT(exo.column("time_s").size(), 9000U) << "telemetry lost most of the run";
    const ctl::ContactQualitySettings settings;  // the shipped 10 N clamp
    ctl::ContactQualitySettings thimble_settings;
    thimble_settings.clamp_n = 1.5;  // config/devices/thimble.yaml safety.max_force_n
    // The user's own pad under the plate, from the same run's felt log, lined up on the
    // recording's monotonic origin.
    std::ifstream felt_file(felt_log_);
    std::stringstream felt_text;
    felt_text << felt_file.rdbuf();
    auto felt_devices = devices;
    ASSERT_EQ(ctl::attachFeltLog(felt_devices, ctl::readRecordingInfo(text.str()),
                                 ctl::readFeltLog(felt_text.str()))
                  .size(),
              2U);  // both devices: the finger of each, the thimble's pad;
    std::printf("%s", ctl::formatReport(felt_devices, settings, thimble_settings).c_str());

    // The loop is closed: the simulated finger, tracking the user, touched the block in both
    // periods, and the sim's reference says so for both devices.
    const auto& exo_reference = exo.column("exo_reference_actuator_force_n");
    const auto contact_ticks = std::count_if(exo_reference.begin(), exo_reference.end(),
                                             [](double f) { return std::abs(f) > 0.5; });
    EXPECT_GT(contact_ticks, 3000) << "the finger pressed the block for a few seconds";
    const ctl::ThimbleReport thimble_report = ctl::thimbleReport(thimble, settings);
    EXPECT_GT(thimble_report.contact_ticks, 3000U);

    // Exoskeleton: no force once the sim has reported no contact for 300 ms (fade 100 ms).
    const auto& command = exo.column("actuator_force_cmd_n");
    const auto free_ticks = settledWithout(exo_reference, 1e-9, 300);
    std::size_t free_count = 0;
    double largest_free_force = 0.0;
    for (std::size_t i = 0; i < command.size(); ++i) {
        if (free_ticks[i]) {
            ++free_count;
            largest_free_force = std::max(largest_free_force, std::abs(command[i]));
        }
    }
    EXPECT_GT(free_count, 1500U) << "the script lifts the finger for ~2 s per period";
    EXPECT_LT(largest_free_force, 0.05);
    // And force while the sim reports contact: the passivity budget credits the sim's moving
    // objects, so the hand moving onto the block is felt (before, the port refused it: 0 N).
    // Not every such tick: a method switch, a contact's first ticks and the controller's cuts
    // pass less. Demo runs of 2026-11-26: 98 % of contact ticks above 0.05 N.
    std::size_t pushing = 0;
    for (std::size_t i = 0; i < command.size(); ++i) {
        pushing += std::abs(exo_reference[i]) > 0.5 && std::abs(command[i]) > 0.05 ? 1U : 0U;
    }
    EXPECT_GT(static_cast<double>(pushing), 0.8 * static_cast<double>(contact_ticks))
        << pushing << " of " << contact_ticks << " contact ticks with force";

    // In contact: never pinned at the clamp (the demo's old failure: 61 % of contact ticks),
    // and passive. Chatter: the target is 5 % of the mean force; this run, with its six live
    // method switches and the first contact after start, measured 1.8-8.3 % in five runs
    // (the demo, one method per 12 s: 1.6-3.6 %; docs/benchmarks.md, "Closed loop",
    // 2026-11-26, second section). Asserted at 15 %, with room for a loaded CI machine:
    // constraints that followed the tracked finger or flipped to a box's side face gave
    // 16-30 %.
    const ctl::ExoskeletonReport report = ctl::exoskeletonReport(exo, settings);
    EXPECT_LE(report.quality.clampFraction(), 0.05);
    EXPECT_LE(report.quality.chatterFraction(), 0.15);
    // Passive with respect to the port and the sim's moving objects together: the device gave
    // the finger no more than the objects' motion put into the coupling (port_safety.hpp).
    EXPECT_LE(report.excessEnergy(), 1e-3) << "the exoskeleton stays passive";
    // Counted from the enable, to the nJ: the port never spends in deficit (allowed: the CSV's
    // 1 nJ rounding on a few ticks), and the deficit the objects' motion books after a tick
    // stays small (the demo's windows: at most 1.5 uJ; docs/benchmarks.md, 2026-11-28 (tenth)).
    EXPECT_LE(report.delivered_in_deficit_j, 1e-7);
    EXPECT_LE(report.worst_balance_j, 1e-5);

    // Thimble: it presses while the sim reports pad contact and sits retracted otherwise.
    const auto& servo = thimble.column("servo_angle_cmd_0_rad");
    const double retract = *std::max_element(servo.begin(), servo.end());
    std::vector<double> pad_force(servo.size());
    for (std::size_t i = 0; i < servo.size(); ++i) {
        pad_force[i] = std::hypot(thimble.column("thimble_reference_force_x_n")[i],
                                  thimble.column("thimble_reference_force_y_n")[i],
                                  thimble.column("thimble_reference_force_z_n")[i]);
    }
    const auto pad_free = settledWithout(pad_force, 1e-9, 300);
    const auto& model_force = thimble.column("thimble_pad_force_model_n");
    std::size_t pressing = 0, pressed_ticks = 0, retracted = 0, free_pad_ticks = 0;
    std::size_t with_force = 0;
    double first_raised_s = -1.0;  // the first tick of a free pad with the plate raised
    double sum_model = 0.0, sum_reference = 0.0;
    for (std::size_t i = 0; i < servo.size(); ++i) {
        if (pad_force[i] > 0.2) {
            ++pressed_ticks;
            pressing += servo[i] < retract - 0.2 ? 1 : 0;
            with_force += model_force[i] > 0.01 ? 1 : 0;
            sum_model += model_force[i];
            sum_reference += pad_force[i];
        }
        if (pad_free[i]) {
            ++free_pad_ticks;
            const bool at_retract = std::abs(servo[i] - retract) < 1e-3;
            retracted += at_retract ? 1 : 0;
            if (!at_retract && first_raised_s < 0.0) {
                first_raised_s = thimble.column("time_s")[i];
            }
        }
    }
    ASSERT_GT(pressed_ticks, 1000U);
    std::printf(
        "thimble: plate off its retract pose on %zu of %zu ticks with a pad force above "
        "0.2 N (%.1f %%)\n",
        pressing, pressed_ticks,
        100.0 * static_cast<double>(pressing) / static_cast<double>(pressed_ticks));
    EXPECT_GT(static_cast<double>(pressing), 0.9 * static_cast<double>(pressed_ticks));
    // And it presses: the force its pad model gives the plate commanded (hapticd's model, a
    // linear pad; what the user's own pad feels is below).
    std::printf(
        "thimble: pad model force above 0.01 N on %.1f %% of those ticks, mean %.3f N against "
        "a mean reference of %.3f N\n",
        100.0 * static_cast<double>(with_force) / static_cast<double>(pressed_ticks),
        sum_model / static_cast<double>(pressed_ticks),
        sum_reference / static_cast<double>(pressed_ticks));
    // 69-98 % seen beside other CPU-heavy tests (2026-11-27, pressed skin only).
    EXPECT_GT(static_cast<double>(with_force), 0.5 * static_cast<double>(pressed_ticks));
    ASSERT_GT(free_pad_ticks, 1000U);
    EXPECT_EQ(retracted, free_pad_ticks)
        << "the plate raised while the pad had been free for 300 ms, first at t = "
        << first_raised_s << " s of the recording";

    // What the user's pad felt: the plate on it while the sim's pad is pressed, off it while
    // the sim's pad is free, and a force of the reference's order: the plate renders the
    // object's surface where it lies against the user's (tracked) finger, and the user's pad
    // (the phalanx under Hertz's law, the FEM's material) feels about two thirds of the sim's
    // force there (demo, 2026-11-28: 0.198 N against 0.319 N; 0.2075 N against 0.321 N here).
    // It felt 0.005 N while the plate took the object's surface from the simulated finger,
    // which the object holds back (docs/benchmarks.md, "Closed loop", thimble row).
    const ctl::DeviceColumns& felt_thimble = felt_devices.at(1);
    std::size_t felt_pressed = 0, felt_free = 0, felt_unknown = 0;
    double largest_free_felt = 0.0, sum_felt = 0.0;
    for (std::size_t i = 0; i < servo.size(); ++i) {
        const double felt = std::hypot(felt_thimble.column("felt_force_x_n")[i],
                                       felt_thimble.column("felt_force_y_n")[i],
                                       felt_thimble.column("felt_force_z_n")[i]);
        if (std::isnan(felt)) {
            ++felt_unknown;
            continue;
        }
        if (pad_force[i] > 0.2) {
            felt_pressed += felt > 0.0 ? 1 : 0;
            sum_felt += felt;
        }
        if (pad_free[i]) {
            ++felt_free;
            largest_free_felt = std::max(largest_free_felt, felt);
        }
    }
    std::printf(
        "thimble: the plate on the user's pad on %.1f %% of the pressed ticks, felt %.4f N "
        "there on average\n",
        100.0 * static_cast<double>(felt_pressed) / static_cast<double>(pressed_ticks),
        sum_felt / static_cast<double>(pressed_ticks));
    EXPECT_LT(felt_unknown, servo.size() / 100) << "the felt log does not cover the recording";
    EXPECT_GT(static_cast<double>(felt_pressed), 0.7 * static_cast<double>(pressed_ticks));
    EXPECT_GT(sum_felt, 0.4 * sum_reference) << "the user's pad feels too little of the contact";
    EXPECT_GT(felt_free, 1000U);

    // The exoskeleton holds the user's finger back: the script's intent takes the pad 3 mm
    // into the block (PressSlideEdgeScript::kPressDepth; the user's skin reaches 3.4 mm there
    // without force, VirtualUser.TheFingerReachesIntoTheBlockAsDeepAsTheScriptPresses), and
    // the rendered force keeps it shallower (demo, 2026-11-27: p50 1.33 mm, max 1.53 mm).
    const ctl::FingerPenetration penetration = ctl::fingerPenetration(felt_devices.at(0));
    EXPECT_GT(penetration.known, exo.column("time_s").size() * 99 / 100);
    ASSERT_GT(penetration.inside, 3000U) << "the finger pressed the block for a few seconds";
    EXPECT_LT(penetration.while_inside_m.p50, 0.003);
    EXPECT_EQ(largest_free_felt, 0.0) << "the retracted plate touched the pad";
}

// The tracker stops while the finger presses the block (a camera covered, a tracking process
// hung): handsim stops sending targets after scene.tracking.timeout_ms without a pose, and
// hapticd fades the force to zero by loop.sim_timeout_ms after the last target. Judged on
// the exoskeleton's own state frames on its bus.
TEST_F(ClosedLoop, ATrackerThatStopsDuringContactTakesTheForceAwayWithinItsTimeouts) {
    const config::SimConfig sim_config = config::loadSimConfig(kConfigDir + "/sim.yaml");
    const config::DaemonConfig daemon_config =
        config::loadDaemonConfig(kConfigDir + "/daemon.yaml");
    const config::DeviceConfig& exo_device = daemon_config.devices.at(0);
    ASSERT_TRUE(exo_device.isExoskeleton());
    ExoListener exo_bus(exo_device);

    // The onset of a contact (free, then pushing): the script presses the block for about
    // 2.5 s of each 6 s period, so 300 ms after the onset the finger is well inside it.
    bool was_free = false;
    bool onset = false;
    for (auto deadline = std::chrono::steady_clock::now() + 20s;
         !onset && std::chrono::steady_clock::now() < deadline;) {
        const auto window = exo_bus.listen(50ms);
        const auto pushing = std::count_if(window.begin(), window.end(), [](const auto& h) {
            return enabledWithForce(h.message, 0.5);
        });
        onset = was_free && pushing > 20;
        was_free = was_free || pushing == 0;
    }
    ASSERT_TRUE(onset) << "no contact onset";
    std::this_thread::sleep_for(300ms);

    const std::int64_t stopped_ns = common::monotonicNowNs();
    ASSERT_TRUE(user_->sendCommand("tracker stop"));
    const auto heard = exo_bus.listen(1500ms);
    // The first state after which the force stays below 0.05 N.
    std::optional<std::int64_t> gone_ns;
    for (const auto& h : heard) {
        if (h.message.type != ExoType::kActuatorState) {
            continue;
        }
        if (std::abs(h.message.actuator.force_n) >= 0.05) {
            gone_ns.reset();
        } else if (!gone_ns) {
            gone_ns = h.at_ns - stopped_ns;
        }
    }
    ASSERT_TRUE(gone_ns.has_value()) << "the force never went away";
    // Still pushing well after the stop: it was the timeouts that took the force, not the
    // script's own release.
    EXPECT_TRUE(std::any_of(heard.begin(), heard.end(), [&](const auto& h) {
        return h.at_ns - stopped_ns > 50'000'000 && enabledWithForce(h.message, 0.3);
    })) << "the force went before the tracker timeout could act";
    // The tracker's last pose may be up to one tracker period (90 Hz) old at the stop, the
    // sim's last step one sim period (100 Hz); the actuator's lag (5 ms) and scheduling on a
    // 2-core VM come on top.
    const std::int64_t bound_ns = (static_cast<std::int64_t>(sim_config.scene.tracking.timeout_ms) +
                                   daemon_config.loop.sim_timeout_ms + 12 + 10 + 5 + 25) *
                                  1'000'000;
    std::printf("tracker stopped: force gone after %.1f ms (bound %.1f ms)\n",
                static_cast<double>(*gone_ns) * 1e-6, static_cast<double>(bound_ns) * 1e-6);
    EXPECT_LE(*gone_ns, bound_ns);

    ASSERT_TRUE(user_->sendCommand("tracker start"));
}

}  // namespace
}  // namespace haptic::testing
