// Freshness by content, judged on the exoskeleton's own frames: the sim input injector sends
// on every 10 ms as before, but old content (the last pair replayed, header and all, or new
// pairs stamped 50 ms before they are sent). hapticd must refuse it, so the force fades to
// zero within sim_timeout_ms as if the sim had gone silent, and comes back when fresh content
// does (the outage is shorter than sim_rearm_after_ms, so no `enable` is needed).

#include <cstdio>

#include "bus_watching_test.hpp"

namespace haptic::testing {
namespace {

using namespace std::chrono_literals;

// The fade's start: sim_timeout_ms (shipped 20) after the last fresh message, which may be one
// injector period (10 ms) plus its stdin poll (10 ms) after the command; the drive's force
// settles within a few ms; and scheduling on a loaded 2-core VM (more under the sanitizers).
constexpr std::int64_t kInjectorLagNs = 20'000'000;
constexpr std::int64_t kDriveSettleNs = 10'000'000;
constexpr std::int64_t kSlackNs = HAPTIC_SANITIZED != 0 ? 100'000'000 : 25'000'000;
constexpr double kNoForceN = 0.05;

class StaleSimInputTest : public BusWatchingTest {
  protected:
    void SetUp() override {
        BusWatchingTest::SetUp();
        if (HasFatalFailure()) {
            return;
        }
        injectAndEnable();
        if (HasFatalFailure()) {
            return;
        }
        ASSERT_TRUE(pushesWithin(5s)) << "the exoskeleton never pushed on the injector's wall";
    }

    bool pushesWithin(std::chrono::milliseconds limit) {
        const auto end = std::chrono::steady_clock::now() + limit;
        while (std::chrono::steady_clock::now() < end) {
            const auto window = exo_bus_.listen(30ms);
            if (std::any_of(window.begin(), window.end(),
                            [](const auto& h) { return enabledWithForce(h.message, 0.3); })) {
                return true;
            }
        }
        return false;
    }

    // Sends `what` to the injector, listens 400 ms, and expects the exoskeleton's force gone
    // within the bound and gone for good; returns how long it took (ms).
    double expectForceGoneAfter(const std::string& what) {
        const std::uint64_t rejected_before = lastStatus().sim_link.rejected;
        const std::int64_t sent_ns = monotonicNs();
        EXPECT_TRUE(injector_->sendCommand(what));
        const auto heard = exo_bus_.listen(400ms);
        // The first state after which the drive never again reports force.
        std::int64_t gone_ns = -1;
        bool states = false;
        for (const auto& h : heard) {
            if (h.message.type != ExoType::kActuatorState) {
                continue;
            }
            states = true;
            if (std::abs(h.message.actuator.force_n) >= kNoForceN) {
                gone_ns = -1;
            } else if (gone_ns < 0) {
                gone_ns = h.at_ns;
            }
        }
        EXPECT_TRUE(states) << what << ": the exoskeleton sent no state";
        EXPECT_GE(gone_ns, 0) << what << ": the force never went away";
        const double gone_ms = static_cast<double>(gone_ns - sent_ns) * 1e-6;
        std::printf("%s: exoskeleton force gone %.1f ms after the command\n", what.c_str(),
                    gone_ms);
        const std::int64_t bound_ns = static_cast<std::int64_t>(sim_timeout_ms_) * 1'000'000 +
                                      kInjectorLagNs + kDriveSettleNs + kSlackNs;
        EXPECT_LE(gone_ns - sent_ns, bound_ns) << what;
        // Refused and counted, not a fault: hapticd keeps RENDERING and waits for fresh input.
        const auto status = lastStatus();
        EXPECT_EQ(status.state, msgs::DaemonState::kRendering) << faultsOf(status);
        EXPECT_GT(status.sim_link.rejected, rejected_before + 20) << what;
        return gone_ms;
    }

    msgs::HapticStatus lastStatus() {
        return waitForStatus("a status stamped now", [](const msgs::HapticStatus& s) {
            return s.header.stamp_ns > monotonicNs() - 100'000'000;
        });
    }

    int sim_timeout_ms_{20};  // config/daemon.yaml, as shipped
};

TEST_F(StaleSimInputTest, AReplayedOrDelayedMessageIsRefusedSoTheForceFadesAsIfTheSimWereSilent) {
    ASSERT_NE(readFile(config_.dir / "daemon.yaml")
                  .find("sim_timeout_ms: " + std::to_string(sim_timeout_ms_)),
              std::string::npos);
    (void)expectForceGoneAfter("replay");
    ASSERT_TRUE(injector_->sendCommand("fresh"));
    EXPECT_TRUE(pushesWithin(1s)) << "fresh input did not bring the force back";
    (void)expectForceGoneAfter("delay 50");
    ASSERT_TRUE(injector_->sendCommand("fresh"));
    EXPECT_TRUE(pushesWithin(1s)) << "fresh input did not bring the force back";
}

// loop.sim_timeout_ms at 150 ms (shipped 20): the force outlasts the replay's start by at
// least the fade's start, 3/4 of the timeout, less the last fresh message's lead (up to one
// injector period and its stdin poll), and still goes within the timeout's bound. With the
// shipped value it went in 15-19 ms here (the test above prints it), with 150 ms in 148-150.
class LongSimTimeoutTest : public StaleSimInputTest {
  protected:
    LongSimTimeoutTest() {
        replaceLine(config_.dir / "daemon.yaml", "sim_timeout_ms: 20 ", "sim_timeout_ms: 150 ");
        sim_timeout_ms_ = 150;
    }
};

TEST_F(LongSimTimeoutTest, TheForceOutlastsARefusedInputForThreeQuartersOfTheTimeout) {
    const double gone_ms = expectForceGoneAfter("replay");
    EXPECT_GE(gone_ms, 0.75 * sim_timeout_ms_ - static_cast<double>(kInjectorLagNs) * 1e-6);
    ASSERT_TRUE(injector_->sendCommand("fresh"));
    EXPECT_TRUE(pushesWithin(1s)) << "fresh input did not bring the force back";
}

}  // namespace
}  // namespace haptic::testing
