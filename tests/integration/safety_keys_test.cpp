// The daemon-wide keys of daemon.yaml whose effect only the running daemon shows, each changed
// from the shipped value and its effect read off what hapticd publishes (the per-device safety
// keys are covered where they act: runtime_test's ExoskeletonSafetyKeys), and a device that
// restarts under a running daemon (runtime_test's Plausibility has the rest of item 4).

#include <sys/mman.h>

#include "device_safety_rig.hpp"
#include "haptic/process/cpu_latency.hpp"
#include "open_files.hpp"

namespace haptic::testing {
namespace {

class TelemetryDecimationTest : public DeviceSafetyTest {
  protected:
    TelemetryDecimationTest() {
        replaceLine(config_.dir / "daemon.yaml", "telemetry_decimation: 1 ",
                    "telemetry_decimation: 10 ");
    }
};

TEST_F(TelemetryDecimationTest, TelemetryCarriesEveryTenthTickOfBothDevices) {
    const auto samples = collectTelemetry(kAllDevices, 1s);
    std::map<std::size_t, std::vector<std::uint64_t>> ticks;
    for (const auto& sample : samples) {
        ticks[sample.device_index].push_back(sample.tick);
    }
    ASSERT_EQ(ticks.size(), 2U);
    for (const auto& [device, device_ticks] : ticks) {
        ASSERT_GT(device_ticks.size(), 10U) << "device " << device;
        for (const std::uint64_t tick : device_ticks) {
            ASSERT_EQ(tick % 10, 0U) << "device " << device;
        }
        // Best effort, as at every tick: a stalled non-RT side may lose a few, not a tenth.
        const std::uint64_t span = (device_ticks.back() - device_ticks.front()) / 10 + 1;
        EXPECT_GT(device_ticks.size(), span * 9 / 10) << "device " << device;
        EXPECT_LE(device_ticks.size(), span) << "device " << device;
    }
}

// loop.status_rate_hz: hapticd snapshots its status that often and publishes each snapshot
// once; the period is read off the snapshots' own stamps (the RT thread's clock), per step of
// their sequence number, so a status the test's reader missed does not count as a long one.
class StatusPeriodTest : public DeviceSafetyTest {
  protected:
    std::vector<double> statusPeriodsMs(std::size_t count) {
        std::vector<msgs::HapticStatus> statuses;
        (void)waitForStatus("statuses", [&](const msgs::HapticStatus& s) {
            statuses.push_back(s);
            return statuses.size() >= count;
        });
        std::vector<double> periods_ms;
        for (std::size_t i = 1; i < statuses.size(); ++i) {
            const auto& before = statuses[i - 1].header;
            const auto& after = statuses[i].header;
            EXPECT_GT(after.seq, before.seq) << "each snapshot is published once";
            if (after.seq > before.seq) {
                periods_ms.push_back(static_cast<double>(after.stamp_ns - before.stamp_ns) * 1e-6 /
                                     static_cast<double>(after.seq - before.seq));
            }
        }
        std::sort(periods_ms.begin(), periods_ms.end());
        return periods_ms;
    }
};

class StatusRateTest : public StatusPeriodTest {
  protected:
    StatusRateTest() {
        replaceLine(config_.dir / "daemon.yaml", "status_rate_hz: 20 ", "status_rate_hz: 5 ");
    }
};

TEST_F(StatusPeriodTest, AtTheShippedRateAStatusEvery50Ms) {
    const auto periods_ms = statusPeriodsMs(21);
    ASSERT_GE(periods_ms.size(), 10U);
    // A snapshot is due at the first 1 ms tick at least a period after the last.
    EXPECT_NEAR(periods_ms[periods_ms.size() / 2], 50.0, 2.0);
}

TEST_F(StatusRateTest, AtFiveHertzAStatusEvery200Ms) {
    const auto periods_ms = statusPeriodsMs(8);
    ASSERT_GE(periods_ms.size(), 5U);
    EXPECT_NEAR(periods_ms[periods_ms.size() / 2], 200.0, 2.0);
}

// loop.realtime, loop.priority and loop.cpu_affinity: hapticd as shipped (realtime: enforce,
// no --realtime override) puts its RT thread, and only it, under SCHED_FIFO at the configured
// priority on the configured core, read back from /proc; where SCHED_FIFO is not permitted it
// refuses to start and says why.
struct ThreadScheduling {
    int policy{-1};
    int rt_priority{-1};
    std::string cpus;  // Cpus_allowed_list
};

ThreadScheduling schedulingOf(const fs::path& task) {
    ThreadScheduling out;
    std::ifstream stat_file(task / "stat");
    const std::string stat((std::istreambuf_iterator<char>(stat_file)),
                           std::istreambuf_iterator<char>());
    // Fields after the command's closing parenthesis, from the third (state) on.
    std::istringstream fields(stat.substr(stat.rfind(')') + 2));
    std::vector<std::string> field{std::istream_iterator<std::string>(fields),
                                   std::istream_iterator<std::string>()};
    if (field.size() > 38) {
        out.rt_priority = std::stoi(field[40 - 3]);
        out.policy = std::stoi(field[41 - 3]);
    }
    std::ifstream status(task / "status");
    for (std::string line; std::getline(status, line);) {
        if (line.rfind("Cpus_allowed_list:", 0) == 0) {
            out.cpus = line.substr(line.find_first_not_of(" \t", 18));
        }
    }
    return out;
}

class RealtimeKeysTest : public DeviceSafetyTest {
  protected:
    RealtimeKeysTest() {
        daemon_realtime_from_config_ = true;
        replaceLine(config_.dir / "daemon.yaml", "priority: 80 ", "priority: 42 ");
        replaceLine(config_.dir / "daemon.yaml", "cpu_affinity: -1 ", "cpu_affinity: 1 ");
        // Not the subject here, and under enforce it would need the device too
        // (CpuLatencyKeyTest below).
        replaceLine(config_.dir / "daemon.yaml", "cpu_latency_us: 0 ", "cpu_latency_us: -1 ");
    }
    void SetUp() override {
        if (!realtimePermitted(42) || ::sysconf(_SC_NPROCESSORS_ONLN) < 2) {
            GTEST_SKIP() << "needs SCHED_FIFO 42 and mlockall (root, or CAP_SYS_NICE and "
                            "CAP_IPC_LOCK), util-linux's prlimit and setpriv, and two cores";
        }
        DeviceSafetyTest::SetUp();
    }

    // What hapticd's real-time setup asks for, tried on a thread of the test's own and undone.
    static bool realtimePermitted(int priority) {
        bool fifo = false;
        std::thread probe([&] {
            sched_param param{};
            param.sched_priority = priority;
            fifo = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param) == 0;
        });
        probe.join();
        const bool locked = ::mlockall(MCL_CURRENT) == 0;
        if (locked) {
            (void)::munlockall();
        }
        return fifo && locked && ::access("/usr/bin/prlimit", X_OK) == 0 &&
               ::access("/usr/bin/setpriv", X_OK) == 0;
    }
};

TEST_F(RealtimeKeysTest, TheRtThreadRunsAtTheConfiguredPriorityOnTheConfiguredCore) {
    const fs::path tasks = fs::path("/proc") / std::to_string(daemon_->pid()) / "task";
    int rt_threads = 0;
    for (const auto& task : fs::directory_iterator(tasks)) {
        std::ifstream comm_file(task.path() / "comm");
        std::string comm;
        std::getline(comm_file, comm);
        const ThreadScheduling scheduling = schedulingOf(task.path());
        if (comm == "hapticd-rt") {
            ++rt_threads;
            EXPECT_EQ(scheduling.policy, SCHED_FIFO);
            EXPECT_EQ(scheduling.rt_priority, 42);
            EXPECT_EQ(scheduling.cpus, "1");
        } else {
            EXPECT_EQ(scheduling.policy, SCHED_OTHER) << comm;
        }
    }
    EXPECT_EQ(rt_threads, 1);
    EXPECT_THAT(daemon_->stderrText(),
                ::testing::HasSubstr("real-time: mlockall, SCHED_FIFO 42, CPU 1"));
    // Without CAP_SYS_NICE and without LimitRTPRIO, enforce refuses to run the loop at all.
    ASSERT_EQ(daemon_->terminate(), std::optional<int>(0)) << daemon_->stderrText();
    daemon_.reset();
    // No LimitRTPRIO either (prlimit), which would grant SCHED_FIFO without the capability.
    const CommandResult refused =
        runCommand({"/usr/bin/prlimit", "--rtprio=0", "--", "/usr/bin/setpriv",
                    "--inh-caps=-sys_nice", "--bounding-set=-sys_nice", HAPTICD_PATH, "-c",
                    (config_.dir / "daemon.yaml").string(), "--dds-domain", domain()},
                   20s);
    EXPECT_NE(refused.exit_code, 0);
    EXPECT_THAT(refused.err, ::testing::HasSubstr("real-time setup failed ("));
    EXPECT_THAT(refused.err, ::testing::HasSubstr("SCHED_FIFO priority 42 (needs CAP_SYS_NICE"));
}

// loop.cpu_latency_us: hapticd holds its request on the kernel's PM QoS device for as long as
// it runs (the open file is the request), and says so; under enforce, a device it cannot open
// (here made read-only in a mount namespace of the refused run's own) stops the start.
class CpuLatencyKeyTest : public RealtimeKeysTest {
  protected:
    CpuLatencyKeyTest() {
        replaceLine(config_.dir / "daemon.yaml", "cpu_latency_us: -1 ", "cpu_latency_us: 4 ");
    }
    void SetUp() override {
        // Whether this host lets a process make the request at all, asked without the class
        // under test (whose failure must fail the test, not skip it).
        if (::access(process::CpuLatencyRequest::kDevicePath, W_OK) != 0) {
            GTEST_SKIP() << "cannot write " << process::CpuLatencyRequest::kDevicePath
                         << " (root, or the udev rule)";
        }
        RealtimeKeysTest::SetUp();
    }
};

TEST_F(CpuLatencyKeyTest, HapticdHoldsTheRequestWhileItRunsAndEnforceRefusesToRunWithout) {
    const fs::path device = process::CpuLatencyRequest::kDevicePath;
    EXPECT_TRUE(holdsOpen(daemon_->pid(), device));
    EXPECT_THAT(daemon_->stderrText(), ::testing::HasSubstr("CPU wake-up latency held at 4 us"));
    const auto combined = readCpuLatencyUs(device);
    ASSERT_TRUE(combined.has_value()) << "fewer than four bytes read from " << device;
    EXPECT_LE(*combined, 4) << "the kernel combines the holders' requests to the lowest";
    ASSERT_EQ(daemon_->terminate(), std::optional<int>(0)) << daemon_->stderrText();
    daemon_.reset();

    if (runCommand({"/usr/bin/unshare", "-m", "/bin/true"}, 10s).exit_code != 0) {
        GTEST_SKIP() << "no private mount namespace here (unshare -m, CAP_SYS_ADMIN)";
    }
    const fs::path read_only = config_.dir / "read-only-cpu-latency";
    std::ofstream(read_only).close();
    const std::string script = "mount --bind '" + read_only.string() + "' " + device.string() +
                               " && mount -o remount,bind,ro " + device.string() +
                               " || exit 77; exec '" + std::string(HAPTICD_PATH) + "' -c '" +
                               (config_.dir / "daemon.yaml").string() + "' --dds-domain " +
                               domain();
    const CommandResult refused =
        runCommand({"/usr/bin/unshare", "-m", "/bin/sh", "-c", script}, 20s);
    if (refused.exit_code == 77) {
        GTEST_SKIP() << "no mount namespace here: " << refused.err;
    }
    EXPECT_NE(refused.exit_code, 0);
    EXPECT_THAT(refused.err,
                ::testing::HasSubstr("real-time setup failed (CPU latency request: " +
                                     device.string() + ": cannot open: Read-only file system"));
}

// loop.rate_hz at 2 kHz (shipped 1 kHz): the ticks in telemetry come every 0.5 ms by the RT
// thread's own stamps. (Lower rates are refused with the shipped exoskeleton: its coupling's
// passivity margin needs at least 1 kHz, ConfigReferences.)
class LoopRateTest : public DeviceSafetyTest {
  protected:
    LoopRateTest() { replaceLine(config_.dir / "daemon.yaml", "rate_hz: 1000 ", "rate_hz: 2000 "); }
};

TEST_F(LoopRateTest, TheLoopTicksAtTheConfiguredRate) {
    if (HAPTIC_SANITIZED != 0) {
        // It ticked every 1.1 ms there, and the shipped exoskeleton refuses a rate below
        // 1 kHz (its passivity margin), so no other rate an unoptimised hapticd holds is left.
        GTEST_SKIP() << "an unoptimised hapticd cannot tick at 2 kHz";
    }
    const auto samples = collectTelemetry(0, 500ms);
    // Consecutive ticks only, and their median: a sample the reader lost, or a late wake-up
    // (the timer then skips the deadlines it missed), does not move it.
    std::vector<double> periods_ms;
    for (std::size_t i = 1; i < samples.size(); ++i) {
        if (samples[i].tick == samples[i - 1].tick + 1) {
            periods_ms.push_back(
                static_cast<double>(samples[i].stamp_ns - samples[i - 1].stamp_ns) * 1e-6);
        }
    }
    ASSERT_GT(periods_ms.size(), 200U);
    std::sort(periods_ms.begin(), periods_ms.end());
    EXPECT_NEAR(periods_ms[periods_ms.size() / 2], 0.5, 0.05);
    // The status reports the rate the loop was configured with.
    const auto status = waitForStatus("a status", [](const auto&) { return true; });
    EXPECT_EQ(status.loop.rate_hz, 2000.0);
}

// log_level in daemon.yaml: at warn, hapticd's start-up lines at info level are not logged.
class WarnLogLevelTest : public DeviceSafetyTest {
  protected:
    WarnLogLevelTest() {
        replaceLine(config_.dir / "daemon.yaml", "log_level: info ", "log_level: warn ");
    }
};

TEST_F(DeviceSafetyTest, AtTheShippedLogLevelHapticdLogsItsStartAtInfo) {
    (void)waitForStatus("a status", [](const auto&) { return true; });
    EXPECT_THAT(daemon_->stderrText(), ::testing::HasSubstr(" info: local control on "));
}

TEST_F(WarnLogLevelTest, AtWarnHapticdLogsNothingAtInfo) {
    (void)waitForStatus("a status", [](const auto&) { return true; });
    EXPECT_THAT(daemon_->stderrText(), ::testing::Not(::testing::HasSubstr(" info: ")));
}

// rendering.method in the exoskeleton's file is the method hapticd starts with.
class StartingMethodTest : public DeviceSafetyTest {
  protected:
    StartingMethodTest() {
        replaceLine(config_.dir / "devices/exoskeleton.yaml", "method: linearized_subspace ",
                    "method: anisotropic ");
    }
};

TEST_F(StartingMethodTest, HapticdStartsWithTheMethodTheDeviceFileNames) {
    const auto status = waitForStatus("a status", [](const auto&) { return true; });
    EXPECT_EQ(status.rendering_method.view(), "anisotropic");
    EXPECT_THAT(hapticctl({"status"}).out, ::testing::HasSubstr("rendering method: anisotropic"));
}

// The emulated thimble restarts (hapticemu's `reboot`): its heartbeat's uptime goes back,
// hapticd latches fault 104 naming it, and only clear + enable render again.
TEST_F(DeviceSafetyTest, ADeviceThatRebootsLatchesItsOwnFault) {
    ASSERT_TRUE(command("enable"));
    waitForStatus("RENDERING", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kRendering;
    });
    ASSERT_TRUE(thimble_emu_->sendCommand("reboot"));
    const auto status = waitForStatus("FAULT", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kFault && !s.faults.empty();
    });
    ASSERT_EQ(status.faults.size(), 1U) << faultsOf(status);
    EXPECT_EQ(status.faults[0].code, 104U);
    EXPECT_EQ(status.faults[0].device_id.view(), "thimble");
    EXPECT_EQ(status.devices[kThimble].state, msgs::DeviceRunState::kFault);
    const auto text = hapticctl({"status"});
    EXPECT_THAT(text.out, ::testing::HasSubstr("[104] thimble: device rebooted (uptime "));

    // The restarted device runs normally; the fault stays until an operator clears it.
    std::this_thread::sleep_for(200ms);
    EXPECT_EQ(waitForStatus("a status", [](const auto&) { return true; }).state,
              msgs::DaemonState::kFault);
    ASSERT_TRUE(command("clear"));
    waitForStatus("IDLE after clear", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kIdle && s.faults.empty();
    });
}

}  // namespace
}  // namespace haptic::testing
