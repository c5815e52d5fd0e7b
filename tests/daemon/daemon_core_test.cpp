#include "haptic/daemon/daemon_core.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "allocation_counter.hpp"

namespace haptic::daemon {
namespace {

using ::testing::DoubleNear;
using ::testing::Eq;
using ::testing::Gt;

constexpr std::int64_t kMs = 1'000'000;

// The sim's CLOCK_MONOTONIC when the test's time is 0: a booted host's, never 0 or less.
constexpr std::int64_t kSimClockAtZero = 1000 * 1000 * kMs;

// Each message is newer than the last, as handsim's are (seq +1), stamped when it was sent:
// hapticd judges its age by the stamp (a test that offers a message at t passes t).
msgs::MessageHeader nextHeader(std::string_view device, std::int64_t sent_ns) {
    static std::uint64_t seq = 0;
    msgs::MessageHeader header;
    header.seq = ++seq;
    header.stamp_ns = kSimClockAtZero + sent_ns;
    header.source_id.assign(device);
    return header;
}

msgs::ConstraintSet validConstraintSet(std::string_view device, std::int64_t sent_ns = 0) {
    msgs::ConstraintSet message;
    message.header = nextHeader(device, sent_ns);
    message.dof = 3;
    message.q_sim_rad = {0.1, 0.2, 0.3};
    msgs::LinearConstraint constraint;
    constraint.a = {0.0, -0.05, -0.02};
    constraint.b = -0.01;
    message.constraints.push_back(constraint);
    return message;
}

// A valid constraint set with its header's seq and stamp as given (the sim's own clock).
msgs::ConstraintSet stampedConstraintSet(std::string_view device, std::uint64_t seq,
                                         std::int64_t stamp_ns) {
    msgs::ConstraintSet message = validConstraintSet(device);
    message.header.seq = seq;
    message.header.stamp_ns = stamp_ns;
    return message;
}

msgs::ContactSurface validContactSurface(std::string_view device, std::int64_t sent_ns = 0) {
    msgs::ContactSurface message;
    message.header = nextHeader(device, sent_ns);
    msgs::ContactSample sample;
    sample.normal_device = {0.0, 0.0, -1.0};
    sample.weight = 1.0;
    message.samples.push_back(sample);
    return message;
}

// The sim over DDS, as if on another host: its clock is learnt (over iceoryx, the rule of
// DaemonCoreFreshness.OverIceoryx...).
class DaemonCoreTest : public ::testing::Test {
  protected:
    DaemonCoreTest()
        : sut(CoreSettings{1000.0,
                           20 * kMs,
                           100 * kMs,
                           50 * kMs,
                           "subspace",
                           msgs::SimTransport::kDds,
                           {"subspace"}},
              {DeviceDescriptor{"exo_index", msgs::DeviceKind::kExoskeleton, 3, 1},
               DeviceDescriptor{"thimble_index", msgs::DeviceKind::kThimble, 3, 3}}) {
        sut.markStarted(0);
    }

    // Runs ticks at 1 kHz from `from` for `count` ticks and returns the next time.
    std::int64_t runTicks(std::int64_t from, int count) {
        std::int64_t t = from;
        for (int i = 0; i < count; ++i) {
            t += kMs;
            sut.update(t, TickTiming{5.0, 1000.0, 1.0, 2.0, 1.0});
        }
        return t;
    }

    DaemonCore sut;
};

TEST_F(DaemonCoreTest, StartsIdleWithNoSimInputAndZeroFade) {
    EXPECT_THAT(sut.state(), Eq(msgs::DaemonState::kIdle));
    runTicks(0, 5);
    EXPECT_THAT(sut.simFade(0), Eq(0.0));
}

TEST_F(DaemonCoreTest, FreshInputRampsForceUpWithoutAStep) {
    std::int64_t t = 0;
    double previous = sut.simFade(0);
    for (int i = 0; i < 200; ++i) {
        ASSERT_THAT(sut.offerConstraintSet(0, validConstraintSet("exo_index", t), t),
                    Eq(InputRejection::kNone));
        t = runTicks(t, 1);
        const double fade = sut.simFade(0);
        EXPECT_LE(fade - previous, 1.0 / 100.0 + 1e-12) << "rose faster than the fade-in ramp";
        previous = fade;
    }
    EXPECT_THAT(sut.simFade(0), DoubleNear(1.0, 1e-12));
}

TEST_F(DaemonCoreTest, StaleInputFadesToZeroWithinTheTimeoutAndNeverRises) {
    std::int64_t t = 0;
    for (int i = 0; i < 200; ++i) {
        (void)sut.offerConstraintSet(0, validConstraintSet("exo_index", t), t);
        t = runTicks(t, 1);
    }
    const std::int64_t last_input = t - kMs;
    double previous = sut.simFade(0);
    for (int i = 0; i < 30; ++i) {
        t = runTicks(t, 1);
        EXPECT_LE(sut.simFade(0), previous);
        previous = sut.simFade(0);
        if (t - last_input >= 20 * kMs) {
            EXPECT_THAT(sut.simFade(0), Eq(0.0)) << "force left after the 20 ms timeout";
        }
    }
}

// Fresh by content, not by arrival: a replayed or duplicated message (seq not advancing) is
// refused and does not hold the input alive; a restarted sim (seq from 1 again, later stamp)
// is taken at once.
TEST_F(DaemonCoreTest, AReplayedOrDuplicatedMessageIsRefusedAndDoesNotRenewTheInput) {
    std::int64_t t = 0;
    const msgs::ConstraintSet first = validConstraintSet("exo_index");
    const msgs::ConstraintSet second = validConstraintSet("exo_index");
    EXPECT_EQ(sut.offerConstraintSet(0, first, t), InputRejection::kNone);
    EXPECT_EQ(sut.offerConstraintSet(0, second, t), InputRejection::kNone);
    t = runTicks(t, 100);
    EXPECT_EQ(sut.offerConstraintSet(0, second, t), InputRejection::kNotNewer) << "a duplicate";
    EXPECT_EQ(sut.offerConstraintSet(0, first, t), InputRejection::kNotNewer) << "a replay";
    msgs::ConstraintSet restamped = second;
    restamped.header.stamp_ns += 100 * kMs;
    EXPECT_EQ(sut.offerConstraintSet(0, restamped, t), InputRejection::kNotNewer)
        << "the same content, stamped again";
    EXPECT_EQ(sut.rejectedCount(0, InputRejection::kNotNewer), 3U);
    t = runTicks(t, 1);  // the fade moves only in a tick: a renewed input would lift it
    EXPECT_EQ(sut.simFade(0), 0.0) << "the replays kept a stale input alive";
    msgs::ConstraintSet restarted = validConstraintSet("exo_index", t);
    restarted.header.seq = 1;
    EXPECT_EQ(sut.offerConstraintSet(0, restarted, t), InputRejection::kNone);
}

// A sim on another host stamps with its own clock: what counts is the delay relative to the
// quickest message. A message that took longer than sim_timeout_ms (20 ms) beyond that is
// refused however new its seq; the clocks' offset itself, and a slow drift of it, are not.
TEST_F(DaemonCoreTest, AMessageDelayedBeyondTheSimTimeoutIsRefusedWhateverTheClocksOffset) {
    constexpr std::int64_t kOtherClock = 5'000'000 * kMs;  // the sim host booted long before
    std::uint64_t seq = 0;
    const auto sent = [&](std::int64_t stamp_ns) {
        msgs::ConstraintSet message = validConstraintSet("exo_index");
        message.header.seq = ++seq;
        message.header.stamp_ns = kOtherClock + stamp_ns;
        return message;
    };
    std::int64_t t = 0;
    // 100 Hz, each message 2-4 ms on its way.
    for (int i = 0; i < 50; ++i) {
        EXPECT_EQ(sut.offerConstraintSet(0, sent(t - (2 + i % 3) * kMs), t), InputRejection::kNone)
            << i;
        t = runTicks(t, 10);
    }
    EXPECT_EQ(sut.offerConstraintSet(0, sent(t - 21 * kMs), t), InputRejection::kNone)
        << "19 ms slower than the quickest: within the timeout";
    EXPECT_EQ(sut.offerConstraintSet(0, sent(t - 25 * kMs), t), InputRejection::kDelayed)
        << "23 ms slower than the quickest";
    EXPECT_EQ(sut.rejectedCount(0, InputRejection::kDelayed), 1U);
    // Only delayed messages for 30 ms: the input goes stale and the force fades.
    for (int i = 0; i < 3; ++i) {
        t = runTicks(t, 10);
        EXPECT_EQ(sut.offerConstraintSet(0, sent(t - 40 * kMs), t), InputRejection::kDelayed);
    }
    t = runTicks(t, 1);
    EXPECT_EQ(sut.simFade(0), 0.0) << "delayed messages kept the input alive";
    // The sim host's clock running 100 ppm slow for 10 minutes (60 ms): never refused.
    for (int i = 0; i < 60'000; ++i) {
        t += 10 * kMs;
        const std::int64_t stamp = t - 3 * kMs - static_cast<std::int64_t>(1e-4 * t);
        ASSERT_EQ(sut.offerConstraintSet(0, sent(stamp), t), InputRejection::kNone) << i;
    }
    // A restarted sim (seq from 1 again, a later stamp) a second later, its messages now 1 s
    // on their way (a sim host whose clock was stepped): its clock offset starts afresh.
    const std::int64_t last_stamp = t - 3 * kMs - static_cast<std::int64_t>(1e-4 * t);
    seq = 0;
    t += 1000 * kMs;
    EXPECT_EQ(sut.offerConstraintSet(0, sent(last_stamp + kMs), t), InputRejection::kNone);
    t += 10 * kMs;
    EXPECT_EQ(sut.offerConstraintSet(0, sent(last_stamp + 11 * kMs), t), InputRejection::kNone);
    EXPECT_EQ(sut.rejectedCount(0, InputRejection::kDelayed), 4U);
}

// One corrupt stamp must not lock the input out: a stamp of 0 or less, or one far ahead of the
// sim's learnt clock (which, taken as the quickest message, would make every later one read
// as delayed), is refused and leaves the learnt clock as it was. Stamps at the int64 limits
// do not overflow the arithmetic (UBSan).
TEST_F(DaemonCoreTest, ACorruptStampIsRefusedAndTheMessagesAfterItAreTaken) {
    std::int64_t t = 0;
    for (int i = 0; i < 20; ++i) {
        ASSERT_EQ(sut.offerConstraintSet(0, validConstraintSet("exo_index", t - 3 * kMs), t),
                  InputRejection::kNone);
        t = runTicks(t, 10);
    }
    msgs::ConstraintSet zero = validConstraintSet("exo_index", t);
    zero.header.stamp_ns = 0;
    EXPECT_EQ(sut.offerConstraintSet(0, zero, t), InputRejection::kBadStamp);
    zero.header.stamp_ns = std::numeric_limits<std::int64_t>::min();
    EXPECT_EQ(sut.offerConstraintSet(0, zero, t), InputRejection::kBadStamp);
    msgs::ConstraintSet ahead = validConstraintSet("exo_index", t + 1000 * kMs);
    EXPECT_EQ(sut.offerConstraintSet(0, ahead, t), InputRejection::kStampAhead);
    ahead = validConstraintSet("exo_index");
    ahead.header.stamp_ns = std::numeric_limits<std::int64_t>::max();
    EXPECT_EQ(sut.offerConstraintSet(0, ahead, t), InputRejection::kStampAhead);
    EXPECT_EQ(sut.offerConstraintSet(0, validConstraintSet("exo_index", t - 20 * kMs), t),
              InputRejection::kNone)
        << "17 ms slower than the quickest, and the corrupt stamps did not count as quickest";
    EXPECT_EQ(sut.offerConstraintSet(0, validConstraintSet("exo_index", t - 3 * kMs), t),
              InputRejection::kNone);
    EXPECT_EQ(sut.rejectedCount(0, InputRejection::kBadStamp), 2U);
    EXPECT_EQ(sut.rejectedCount(0, InputRejection::kStampAhead), 2U);
}

// A stall longer than the devices' command timeout is hapticd's own fault, but only when a
// device hears it: with every device offline there is no one to time out.
// One exoskeleton rendered with `subspace`; the caller sets what its test is about.
CoreSettings oneMethodSettings() {
    CoreSettings settings;
    settings.known_methods = {"subspace"};
    settings.sim_transport = msgs::SimTransport::kDds;  // the sim's clock is learnt
    settings.rendering_method = "subspace";
    return settings;
}
const std::vector<DeviceDescriptor> kOneExoskeleton{
    DeviceDescriptor{"exo", msgs::DeviceKind::kExoskeleton, 3, 1}};

TEST(DaemonCoreStall, AStallIsItsOwnFaultOnlyWhileADeviceIsOnline) {
    CoreSettings settings = oneMethodSettings();
    settings.stall_limit_ns = 10 * kMs;
    DaemonCore core(settings, kOneExoskeleton);
    core.markStarted(0);
    core.update(50 * kMs, TickTiming{});
    EXPECT_EQ(core.stateMachine().faultCount(), 0U) << "no device online";
    DeviceReport online;
    online.status_bits = static_cast<std::uint32_t>(msgs::DeviceStatusBit::kOnline);
    core.setDeviceReport(0, online);
    core.update(51 * kMs, TickTiming{});
    core.update(61 * kMs, TickTiming{});  // exactly the limit: not a stall
    EXPECT_EQ(core.stateMachine().faultCount(), 0U);
    core.update(72 * kMs, TickTiming{});
    ASSERT_EQ(core.stateMachine().faultCount(), 1U);
    EXPECT_EQ(core.stateMachine().fault(0).code, kFaultLoopStalled);
    EXPECT_EQ(core.state(), msgs::DaemonState::kFault);
    EXPECT_EQ(core.lastStallEndNs(), 72 * kMs);
}

// A one-exoskeleton core, started, with the overrun policy `limit` within `window_ns` and its
// device online unless told otherwise.
std::unique_ptr<DaemonCore> overrunCore(std::uint32_t limit, std::int64_t window_ns,
                                        bool online = true) {
    CoreSettings settings = oneMethodSettings();
    settings.overrun_limit = limit;
    settings.overrun_window_ns = window_ns;
    auto core = std::make_unique<DaemonCore>(settings, kOneExoskeleton);
    core->markStarted(0);
    if (online) {
        DeviceReport report;
        report.status_bits = static_cast<std::uint32_t>(msgs::DeviceStatusBit::kOnline);
        core->setDeviceReport(0, report);
    }
    return core;
}

// The overrun policy (loop.overrun_limit within loop.overrun_window_ms): as many overruns
// spread wider than the window are only counted; the limit within it is hapticd's own fault,
// raised once until cleared.
TEST(DaemonCoreOverruns, TheLimitWithinTheWindowIsItsOwnFaultSpreadWiderItIsOnlyCounted) {
    auto owned = overrunCore(10, 100 * kMs);
    DaemonCore& core = *owned;
    TickTiming overrun;
    overrun.compute_us = 1200.0;  // past the 1000 us period
    std::int64_t t = 0;
    auto tick = [&](const TickTiming& timing) {
        t += kMs;
        core.update(t, timing);
    };
    // One overrun every 12 ms: any 10 of them span 108 ms, wider than the window.
    for (int i = 0; i < 400; ++i) {
        tick(i % 12 == 0 ? overrun : TickTiming{});
    }
    EXPECT_EQ(core.stateMachine().faultCount(), 0U);
    tick(TickTiming{});
    // Quiet for longer than the window, then one every 11 ms: the 10th lands 99 ms after
    // the first, within the window, and raises; the 9th did not.
    for (int i = 0; i < 150; ++i) {
        tick(TickTiming{});
    }
    for (int n = 1; n <= 10; ++n) {
        EXPECT_EQ(core.stateMachine().faultCount(), 0U) << "before overrun " << n;
        tick(overrun);
        for (int i = 0; n < 10 && i < 10; ++i) {
            tick(TickTiming{});
        }
    }
    ASSERT_EQ(core.stateMachine().faultCount(), 1U);
    EXPECT_EQ(core.stateMachine().fault(0).code, kFaultLoopOverrunning);
    EXPECT_EQ(core.stateMachine().fault(0).device_id.view(), "hapticd");
    EXPECT_EQ(std::string(core.stateMachine().fault(0).message.view()),
              "loop overrunning: 10 ticks past the 1000 us period within 100 ms");
    EXPECT_EQ(core.state(), msgs::DaemonState::kFault);
    for (int i = 0; i < 100; ++i) {
        tick(overrun);
    }
    EXPECT_EQ(core.stateMachine().faultCount(), 1U) << "raised once until cleared";
}

// The window's edge: 10 overruns exactly 100 ms apart end to end still count (within means
// <=), 101 ms do not; and a limit of 1 makes every overrun a fault.
TEST(DaemonCoreOverruns, TheWindowIncludesItsEdgeAndALimitOfOneRaisesAtOnce) {
    TickTiming overrun;
    overrun.read_us = 1500.0;
    for (const std::int64_t spacing_us : {11'111, 11'223}) {  // 9 gaps: 99.999 ms, 101.0 ms
        auto core = overrunCore(10, 100 * kMs);
        for (int n = 0; n < 10; ++n) {
            const std::int64_t at = kMs + n * spacing_us * 1000;
            core->update(at, overrun);
            // Plain ticks between them: the loop keeps its rate (DaemonCoreRate).
            for (int k = 1; n < 9 && k <= 11; ++k) {
                core->update(at + k * kMs, TickTiming{});
            }
        }
        EXPECT_EQ(core->stateMachine().faultCount(), spacing_us < 11'112 ? 1U : 0U)
            << spacing_us << " us apart";
    }
    auto core = overrunCore(1, 100 * kMs);
    core->update(kMs, TickTiming{});
    EXPECT_EQ(core->stateMachine().faultCount(), 0U);
    core->update(2 * kMs, overrun);
    EXPECT_EQ(core->stateMachine().faultCount(), 1U);
}

// After a clear the overrun policy counts afresh and raises again, even when another fault
// came first (the latch followed an empty fault list, which that fault kept from it).
TEST(DaemonCoreOverruns, AClearReArmsTheFaultEvenWhenAnotherComesFirst) {
    auto owned = overrunCore(3, 100 * kMs);
    DaemonCore& core = *owned;
    TickTiming overrun;
    overrun.compute_us = 1200.0;
    std::int64_t t = 0;
    for (int i = 0; i < 3; ++i) {
        core.update(t += kMs, overrun);
    }
    ASSERT_EQ(core.stateMachine().faultCount(), 1U);
    msgs::HapticCommand clear;
    clear.kind = msgs::CommandKind::kClearFault;
    msgs::HapticCommandReply reply;
    ASSERT_TRUE(core.applyCommand(clear, t, reply).accepted) << reply.message.view();
    core.raiseFault(100, "exo", "heartbeat lost");
    for (int i = 0; i < 3; ++i) {
        core.update(t += kMs, overrun);
    }
    ASSERT_EQ(core.stateMachine().faultCount(), 2U);
    EXPECT_EQ(core.stateMachine().fault(1).code, kFaultLoopOverrunning);
}

TEST(DaemonCoreOverruns, OffAtZeroAndWithNoDeviceOnline) {
    TickTiming overrun;
    overrun.write_us = 5000.0;
    for (const bool online : {false, true}) {
        auto core = overrunCore(online ? 0 : 5, 1000 * kMs, online);
        for (int i = 1; i <= 100; ++i) {
            core->update(i * kMs, overrun);
        }
        EXPECT_EQ(core->stateMachine().faultCount(), 0U) << (online ? "limit 0" : "offline");
    }
}

// Late wake-ups that no tick's work shows and no gap makes a stall: a loop ticking below half
// its rate over a whole window is hapticd's own fault (kFaultLoopTooSlow), raised once.
TEST(DaemonCoreRate, BelowHalfTheRateOverAWindowIsItsOwnFaultAboveItIsNot) {
    for (const std::int64_t period_us : {1'900, 2'100}) {  // 526 Hz, 476 Hz
        auto owned = overrunCore(100, 1000 * kMs);
        DaemonCore& core = *owned;
        for (std::int64_t t = kMs; t <= 3000 * kMs; t += period_us * 1000) {
            core.update(t, TickTiming{});
        }
        if (period_us < 2'000) {
            EXPECT_EQ(core.stateMachine().faultCount(), 0U) << period_us << " us";
            continue;
        }
        ASSERT_EQ(core.stateMachine().faultCount(), 1U) << "raised once";
        EXPECT_EQ(core.stateMachine().fault(0).code, kFaultLoopTooSlow);
        EXPECT_EQ(core.stateMachine().fault(0).device_id.view(), "hapticd");
        EXPECT_THAT(std::string(core.stateMachine().fault(0).message.view()),
                    ::testing::MatchesRegex("loop too slow: 476 Hz over 100[0-9] ms "
                                            "\\(rate 1000 Hz\\)"));
        EXPECT_EQ(core.state(), msgs::DaemonState::kFault);
    }
}

// A stall is its own fault (110): the rate window restarts after it instead of adding a
// second fault for the same silence; off with the overrun policy and with no device online.
TEST(DaemonCoreRate, AStallRestartsTheWindowAndThePolicyCanBeOff) {
    CoreSettings settings = oneMethodSettings();
    settings.stall_limit_ns = 10 * kMs;
    settings.overrun_limit = 100;
    settings.overrun_window_ns = 100 * kMs;
    DaemonCore core(settings, kOneExoskeleton);
    core.markStarted(0);
    DeviceReport online;
    online.status_bits = static_cast<std::uint32_t>(msgs::DeviceStatusBit::kOnline);
    core.setDeviceReport(0, online);
    std::int64_t t = 0;
    for (int i = 0; i < 50; ++i) {
        core.update(t += kMs, TickTiming{});
    }
    core.update(t += 80 * kMs, TickTiming{});  // stalled: 50 ticks in 130 ms
    for (int i = 0; i < 200; ++i) {
        core.update(t += kMs, TickTiming{});
    }
    ASSERT_EQ(core.stateMachine().faultCount(), 1U);
    EXPECT_EQ(core.stateMachine().fault(0).code, kFaultLoopStalled);

    for (const bool online_device : {false, true}) {
        auto off = overrunCore(online_device ? 0 : 100, 100 * kMs, online_device);
        for (std::int64_t at = 5 * kMs; at <= 1000 * kMs; at += 5 * kMs) {  // 200 Hz
            off->update(at, TickTiming{});
        }
        EXPECT_EQ(off->stateMachine().faultCount(), 0U)
            << (online_device ? "policy off" : "no device online");
    }
}

// A window shorter than 100 periods is stretched to them: one late wake-up in a 5 ms window
// is not a slow loop. And a clear re-arms the fault even when another one (here 111 of the
// same slow loop) was raised again before the next window closed.
TEST(DaemonCoreRate, AShortWindowIsStretchedAndAClearReArmsTheFault) {
    auto owned = overrunCore(100, 5 * kMs);
    DaemonCore& core = *owned;
    std::int64_t t = 0;
    for (int i = 0; i < 50; ++i) {
        core.update(t += kMs, TickTiming{});
    }
    core.update(t += 4 * kMs, TickTiming{});  // one late wake-up
    for (int i = 0; i < 250; ++i) {
        core.update(t += kMs, TickTiming{});
    }
    EXPECT_EQ(core.stateMachine().faultCount(), 0U);

    auto slow = overrunCore(1, 1000 * kMs);
    TickTiming overrun;
    overrun.compute_us = 1500.0;
    t = 0;
    const auto tick400Hz = [&](const TickTiming& timing) {
        for (int i = 0; i < 400; ++i) {  // one second
            slow->update(t += 2'500'000, timing);
        }
    };
    tick400Hz(TickTiming{});
    tick400Hz(TickTiming{});
    ASSERT_EQ(slow->stateMachine().faultCount(), 1U);
    EXPECT_EQ(slow->stateMachine().fault(0).code, kFaultLoopTooSlow);
    msgs::HapticCommand clear;
    clear.kind = msgs::CommandKind::kClearFault;
    msgs::HapticCommandReply reply;
    ASSERT_TRUE(slow->applyCommand(clear, t, reply).accepted) << reply.message.view();
    ASSERT_EQ(slow->stateMachine().faultCount(), 0U);
    slow->update(t += 2'500'000, overrun);  // 111 at once (limit 1)
    ASSERT_GE(slow->stateMachine().faultCount(), 1U);
    EXPECT_EQ(slow->stateMachine().fault(0).code, kFaultLoopOverrunning);
    tick400Hz(TickTiming{});
    tick400Hz(TickTiming{});
    ASSERT_EQ(slow->stateMachine().faultCount(), 2U) << "114 raised again after the clear, once";
    EXPECT_EQ(slow->stateMachine().fault(1).code, kFaultLoopTooSlow);
}

// The re-arm policy (loop.sim_rearm_after_ms): a short outage fades out and back in by itself;
// after a longer one the device renders again only after a new enable, however fresh its
// input is; input that was never fresh since the enable is not an outage.
// The hardware E-stop input: pressed or silent, E-STOP at once (so the gain of this very tick
// is 0) from any state, recorded once per engagement, and `clear` refused until released.
TEST(DaemonCoreHardwareEstop, PressedOrSilentStopsAtOnceAndOnlyAReleasedRelayLetsClearThrough) {
    DaemonCore core(oneMethodSettings(), kOneExoskeleton);
    msgs::HapticCommandReply reply;
    auto command = [&](msgs::CommandKind kind) {
        msgs::HapticCommand message;
        message.kind = kind;
        return core.applyCommand(message, 0, reply);
    };
    core.setHardwareEstop(HardwareEstop::kPressed, "0x0e0 on exo's bus");
    EXPECT_EQ(core.state(), msgs::DaemonState::kInit) << "INIT is left only by the loop start";
    core.markStarted(0);

    core.setHardwareEstop(HardwareEstop::kAwaitingFirstStatus, "0x0e0 on exo's bus");
    EXPECT_EQ(core.state(), msgs::DaemonState::kIdle);
    EXPECT_FALSE(command(msgs::CommandKind::kEnable).accepted);
    EXPECT_THAT(std::string(reply.message.view()), ::testing::HasSubstr("first status"));

    core.setHardwareEstop(HardwareEstop::kReleased, "0x0e0 on exo's bus");
    ASSERT_TRUE(command(msgs::CommandKind::kEnable).accepted);
    for (std::int64_t t = 1; t <= 200; ++t) {
        (void)core.offerConstraintSet(0, validConstraintSet("exo", t * kMs), t * kMs);
        core.update(t * kMs, TickTiming{});
    }
    ASSERT_GT(core.outputGain(0), 0.0);

    core.setHardwareEstop(HardwareEstop::kPressed, "0x0e0 on exo's bus");
    EXPECT_EQ(core.state(), msgs::DaemonState::kEstop);
    EXPECT_EQ(core.outputGain(0), 0.0) << "the tick that reads the press sends no force";
    core.setHardwareEstop(HardwareEstop::kPressed, "0x0e0 on exo's bus");
    ASSERT_EQ(core.stateMachine().faultCount(), 1U) << "a lasting press is recorded once";
    EXPECT_EQ(core.stateMachine().fault(0).code, kFaultEstopPressed);
    EXPECT_THAT(std::string(core.stateMachine().fault(0).message.view()),
                ::testing::HasSubstr("0x0e0 on exo's bus"));
    EXPECT_FALSE(command(msgs::CommandKind::kClearFault).accepted);
    EXPECT_THAT(std::string(reply.message.view()), ::testing::HasSubstr("release it"));
    EXPECT_FALSE(command(msgs::CommandKind::kEnable).accepted);

    core.setHardwareEstop(HardwareEstop::kSilent, "0x0e0 on exo's bus");
    ASSERT_EQ(core.stateMachine().faultCount(), 2U);
    EXPECT_EQ(core.stateMachine().fault(1).code, kFaultEstopRelaySilent);
    EXPECT_FALSE(command(msgs::CommandKind::kClearFault).accepted);

    core.setHardwareEstop(HardwareEstop::kReleased, "0x0e0 on exo's bus");
    EXPECT_EQ(core.state(), msgs::DaemonState::kEstop) << "releasing re-arms nothing";
    ASSERT_TRUE(command(msgs::CommandKind::kClearFault).accepted);
    EXPECT_EQ(core.state(), msgs::DaemonState::kIdle);
    EXPECT_EQ(core.stateMachine().faultCount(), 0U);

    // From FAULT too: E-STOP wins.
    core.raiseFault(100, "exo", "heartbeat lost");
    ASSERT_EQ(core.state(), msgs::DaemonState::kFault);
    core.setHardwareEstop(HardwareEstop::kSilent, "0x0e0 on exo's bus");
    EXPECT_EQ(core.state(), msgs::DaemonState::kEstop);
}

// One exoskeleton with the re-arm policy at 250 ms (loop.sim_rearm_after_ms), started, and
// an operator's enable to send.
class RearmCore {
  public:
    RearmCore() : core(settings(), kOneExoskeleton) { core.markStarted(0); }
    bool enable(std::int64_t t) {
        msgs::HapticCommand command;
        command.kind = msgs::CommandKind::kEnable;
        return core.applyCommand(command, t, reply).accepted;
    }
    DaemonCore core;
    msgs::HapticCommandReply reply;

  private:
    static CoreSettings settings() {
        CoreSettings settings = oneMethodSettings();
        settings.sim_rearm_after_ns = 250 * kMs;
        return settings;
    }
};

TEST(DaemonCoreRearm, ALongSimOutageWhileRenderingNeedsANewEnable) {
    RearmCore rig;
    DaemonCore& core = rig.core;
    msgs::HapticCommandReply& reply = rig.reply;
    std::int64_t t = 0;
    auto run = [&](int ticks, bool feed) {
        for (int i = 0; i < ticks; ++i) {
            if (feed) {
                (void)core.offerConstraintSet(0, validConstraintSet("exo", t), t);
            }
            t += kMs;
            core.update(t, TickTiming{});
        }
    };
    ASSERT_TRUE(rig.enable(t));
    run(400, false);  // the sim starts late: not an outage
    EXPECT_FALSE(core.awaitingEnable(0));
    run(200, true);
    EXPECT_DOUBLE_EQ(core.outputGain(0), 1.0);
    run(200, false);  // 200 ms: fades out, comes back by itself
    EXPECT_EQ(core.outputGain(0), 0.0);
    run(200, true);
    EXPECT_FALSE(core.awaitingEnable(0));
    EXPECT_DOUBLE_EQ(core.outputGain(0), 1.0);
    run(300, false);  // 300 ms: past the re-arm limit
    EXPECT_TRUE(core.awaitingEnable(0));
    run(300, true);  // fresh again, but no force without the operator
    EXPECT_EQ(core.outputGain(0), 0.0);
    EXPECT_EQ(core.state(), msgs::DaemonState::kRendering);
    msgs::HapticStatus status;
    core.fillStatus(t, status);
    EXPECT_TRUE(status.devices[0].awaiting_enable);
    ASSERT_TRUE(rig.enable(t)) << "enable while RENDERING re-arms";
    EXPECT_FALSE(core.awaitingEnable(0));
    double previous = core.outputGain(0);
    for (int i = 0; i < 150; ++i) {
        run(1, true);
        EXPECT_LE(core.outputGain(0) - previous, 1.0 / 100.0 + 1e-12) << "fades in, no step";
        previous = core.outputGain(0);
    }
    EXPECT_DOUBLE_EQ(core.outputGain(0), 1.0);
    // Leaving RENDERING forgets a pending re-arm: IDLE needs an enable anyway.
    run(300, false);
    ASSERT_TRUE(core.awaitingEnable(0));
    msgs::HapticCommand disable;
    disable.kind = msgs::CommandKind::kDisable;
    ASSERT_TRUE(core.applyCommand(disable, t, reply).accepted);
    run(1, false);
    EXPECT_FALSE(core.awaitingEnable(0));
}

// Over DDS the sim's clock is learnt from its first messages: the median of the first five
// stands for it, so one corrupt stamp among them (the very first, or a restarted sim's first)
// costs a message or two, not the link. And a replay after a silence is still a replay.
TEST_F(DaemonCoreTest, ACorruptStampWhileTheClockIsLearntCostsAMessageNotTheLink) {
    std::int64_t t = 0;
    std::uint64_t seq = 100;
    const auto offer = [&](std::int64_t stamp_ns) {
        return sut.offerConstraintSet(0, stampedConstraintSet("exo_index", ++seq, stamp_ns), t);
    };
    // After a corrupt first message, 18 good ones at 100 Hz: at most one refused, none after
    // the second.
    const auto expectTheStreamTaken = [&](const char* after) {
        int refused = 0;
        for (int i = 0; i < 18; ++i) {
            t = runTicks(t, 10);
            const InputRejection verdict = offer(kSimClockAtZero + t - 3 * kMs);
            refused += verdict == InputRejection::kNone ? 0 : 1;
            EXPECT_TRUE(i < 2 || verdict == InputRejection::kNone) << after << ": " << i;
        }
        EXPECT_LE(refused, 1) << after;
    };
    // The very first message stamped near the int64 limit (taken: nothing to judge it by).
    EXPECT_EQ(offer(std::numeric_limits<std::int64_t>::max() - 1), InputRejection::kNone);
    expectTheStreamTaken("a corrupt first message");
    // A restarted sim (seq from 1 again) whose first message is stamped 1 s ahead.
    seq = 0;
    t = runTicks(t, 10);
    EXPECT_EQ(offer(kSimClockAtZero + t + 1000 * kMs), InputRejection::kNone) << "a restart";
    expectTheStreamTaken("a corrupt first message after a restart");
    // The last message again after 3 s of silence: a replay, not a new start.
    msgs::ConstraintSet last = validConstraintSet("exo_index");
    last.header.seq = seq;
    last.header.stamp_ns = kSimClockAtZero + t - 3 * kMs;
    t = runTicks(t, 3000);
    EXPECT_EQ(sut.offerConstraintSet(0, last, t), InputRejection::kNotNewer);
}

// The sim's clock changes for good while hapticd runs: its host rebooted (seq and stamp both
// go back), its clock was stepped ahead, or it was suspended (its CLOCK_MONOTONIC stood still).
// Refused at first, so the force fades; once that content has formed a stream of its own for
// twice loop.sim_rearm_after_ms (at least 1 s), or after a silence that long, its clock is
// learnt afresh and the force returns only after an operator's enable. A path that is slower
// for good serves old content and is never taken.
TEST(DaemonCoreFreshness, ASimWhoseClockChangedForGoodIsTakenAfterTheReArmAndAnEnable) {
    RearmCore rig;  // re-learnt after 2 x 250 ms, at least 1 s
    DaemonCore& core = rig.core;
    std::int64_t t = 0;
    std::uint64_t seq = 1'000'000;  // the sim has been running for hours
    std::int64_t sim_clock = 0;     // the sim host's clock minus ours
    // 100 Hz for `ms`, each message 3 ms on its way plus `late`; the verdicts.
    auto run = [&](int ms, std::int64_t late = 0) {
        std::vector<InputRejection> verdicts;
        for (int i = 0; i < ms; ++i) {
            if (i % 10 == 0) {
                msgs::ConstraintSet message = validConstraintSet("exo");
                message.header.seq = ++seq;
                message.header.stamp_ns = kSimClockAtZero + sim_clock + t - 3 * kMs - late;
                verdicts.push_back(core.offerConstraintSet(0, message, t));
            }
            t += kMs;
            core.update(t, TickTiming{});
        }
        return verdicts;
    };
    const auto all = [](const std::vector<InputRejection>& verdicts, InputRejection reason) {
        return std::all_of(verdicts.begin(), verdicts.end(),
                           [&](InputRejection v) { return v == reason; });
    };
    const auto reArm = [&] {
        ASSERT_TRUE(all(run(300), InputRejection::kNone));
        EXPECT_TRUE(core.awaitingEnable(0));
        EXPECT_EQ(core.outputGain(0), 0.0) << "no force before the operator's enable";
        ASSERT_TRUE(rig.enable(t));
        EXPECT_TRUE(all(run(200), InputRejection::kNone));
        EXPECT_DOUBLE_EQ(core.outputGain(0), 1.0);
    };
    ASSERT_TRUE(rig.enable(t));
    ASSERT_TRUE(all(run(200), InputRejection::kNone));
    ASSERT_DOUBLE_EQ(core.outputGain(0), 1.0);

    // The sim host rebooted (its clock 10 minutes behind) and handsim counts from 1 again:
    // not newer, for 1 s, then taken.
    sim_clock -= 600'000 * kMs;
    seq = 0;
    std::vector<InputRejection> verdicts = run(990);
    EXPECT_TRUE(all(verdicts, InputRejection::kNotNewer));
    EXPECT_EQ(core.outputGain(0), 0.0);
    verdicts = run(20);
    EXPECT_EQ(verdicts.back(), InputRejection::kNone) << "taken 1 s into the new stream";
    reArm();

    // Its clock stepped 5 s ahead.
    sim_clock += 5000 * kMs;
    verdicts = run(990);
    EXPECT_TRUE(all(verdicts, InputRejection::kStampAhead));
    EXPECT_EQ(core.outputGain(0), 0.0);
    verdicts = run(20);
    EXPECT_EQ(verdicts.back(), InputRejection::kNone);
    reArm();

    // A path slower by 50 ms for good: old content, never taken.
    verdicts = run(3000, 50 * kMs);
    EXPECT_TRUE(all(verdicts, InputRejection::kDelayed));
    EXPECT_EQ(core.outputGain(0), 0.0);
    ASSERT_TRUE(core.awaitingEnable(0));
    // The sim host suspended for 3 s: silent for 3 s, then its clock 3 s behind.
    t += 3000 * kMs;
    sim_clock -= 3000 * kMs;
    core.update(t, TickTiming{});
    reArm();
}

// Over iceoryx the sim is on this host and stamps with our CLOCK_MONOTONIC: a message's age is
// now minus its stamp, from the first message on, with nothing learnt.
TEST(DaemonCoreFreshness, OverIceoryxTheSimSharesOurClockAndItsAgeIsAbsolute) {
    CoreSettings settings = oneMethodSettings();
    settings.sim_transport = msgs::SimTransport::kIceoryx;
    DaemonCore core(settings, kOneExoskeleton);
    core.markStarted(0);
    std::int64_t t = 1000 * kMs;
    std::uint64_t seq = 0;
    const auto offer = [&](std::int64_t stamp_ns) {
        return core.offerConstraintSet(0, stampedConstraintSet("exo", ++seq, stamp_ns), t);
    };
    EXPECT_EQ(offer(t - 25 * kMs), InputRejection::kDelayed) << "the first message is judged too";
    EXPECT_EQ(offer(t - 5 * kMs), InputRejection::kNone);
    EXPECT_EQ(offer(t + kMs), InputRejection::kNone) << "stamped after our tick began";
    const std::uint64_t accepted_seq = seq;
    EXPECT_EQ(offer(t + 30 * kMs), InputRejection::kStampAhead);
    EXPECT_EQ(offer(t - 21 * kMs), InputRejection::kDelayed) << "not judged by the quickest";
    seq = accepted_seq - 1;
    EXPECT_EQ(offer(t), InputRejection::kNotNewer) << "the last accepted seq again";
    for (int i = 0; i < 60'000; ++i) {  // 10 minutes at 100 Hz, each message 3 ms old
        t += 10 * kMs;
        ASSERT_EQ(offer(t - 3 * kMs), InputRejection::kNone) << i;
    }
}

TEST_F(DaemonCoreTest, AStalledTickDoesNotStepForceUp) {
    (void)sut.offerConstraintSet(0, validConstraintSet("exo_index"), 0);
    sut.update(kMs, TickTiming{});
    const double before = sut.simFade(0);
    // The thread stalls for 150 ms and wakes to fresh input.
    (void)sut.offerConstraintSet(0, validConstraintSet("exo_index", 151 * kMs), 151 * kMs);
    sut.update(151 * kMs, TickTiming{});
    EXPECT_LE(sut.simFade(0) - before, 1.0 / 100.0 + 1e-12);
}

TEST_F(DaemonCoreTest, ASimAt100HzWithJitterKeepsFullForce) {
    std::int64_t t = 0;
    for (int frame = 0; frame < 100; ++frame) {
        (void)sut.offerConstraintSet(0, validConstraintSet("exo_index", t), t);
        t = runTicks(t, frame % 2 == 0 ? 8 : 12);  // 10 ms on average, +-2 ms jitter
    }
    for (int frame = 0; frame < 20; ++frame) {
        (void)sut.offerConstraintSet(0, validConstraintSet("exo_index", t), t);
        for (int tick = 0; tick < 12; ++tick) {
            t = runTicks(t, 1);
            EXPECT_THAT(sut.simFade(0), Eq(1.0)) << "force modulated by normal sim jitter";
        }
    }
}

TEST_F(DaemonCoreTest, RejectsNonFiniteAndWrongDeviceInputAndCountsThem) {
    auto nan_q = validConstraintSet("exo_index");
    nan_q.q_sim_rad[1] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THAT(sut.offerConstraintSet(0, nan_q, 0), Eq(InputRejection::kNonFinite));

    auto inf_b = validConstraintSet("exo_index");
    inf_b.constraints[0].b = std::numeric_limits<double>::infinity();
    EXPECT_THAT(sut.offerConstraintSet(0, inf_b, 0), Eq(InputRejection::kNonFinite));

    EXPECT_THAT(sut.offerConstraintSet(0, validConstraintSet("someone_else"), 0),
                Eq(InputRejection::kWrongDevice));

    auto wrong_dof = validConstraintSet("exo_index");
    wrong_dof.dof = 5;
    EXPECT_THAT(sut.offerConstraintSet(0, wrong_dof, 0), Eq(InputRejection::kDofMismatch));

    auto zero_normal = validConstraintSet("exo_index");
    zero_normal.constraints[0].a.fill(0.0);
    EXPECT_THAT(sut.offerConstraintSet(0, zero_normal, 0),
                Eq(InputRejection::kDegenerateConstraint));

    auto corrupt_count = validConstraintSet("exo_index");
    corrupt_count.constraints.count = 1000;
    EXPECT_THAT(sut.offerConstraintSet(0, corrupt_count, 0),
                Eq(InputRejection::kCountOverCapacity));

    auto nan_sample = validContactSurface("thimble_index");
    nan_sample.samples[0].signed_distance_m = std::nan("");
    EXPECT_THAT(sut.offerContactSurface(1, nan_sample, 0), Eq(InputRejection::kNonFinite));

    auto bad_normal = validContactSurface("thimble_index");
    bad_normal.samples[0].normal_device = {0.0, 0.0, 2.0};
    EXPECT_THAT(sut.offerContactSurface(1, bad_normal, 0), Eq(InputRejection::kBadNormal));

    EXPECT_THAT(sut.rejectedCount(0, InputRejection::kNonFinite), Eq(2U));
    sut.update(kMs, TickTiming{});  // the fade moves only in a tick
    EXPECT_THAT(sut.simFade(0), Eq(0.0)) << "a rejected message must not count as fresh input";

    msgs::HapticStatus status;
    sut.fillStatus(kMs, status);
    EXPECT_THAT(status.sim_link.rejected, Eq(8U));
    // By reason, over both devices (the thimble's NaN sample among the non-finite ones).
    std::array<std::uint64_t, msgs::kSimInputRejectionReasons> by_reason{};
    by_reason[msgs::reasonIndex(InputRejection::kNonFinite)] = 3;
    by_reason[msgs::reasonIndex(InputRejection::kWrongDevice)] = 1;
    by_reason[msgs::reasonIndex(InputRejection::kDofMismatch)] = 1;
    by_reason[msgs::reasonIndex(InputRejection::kDegenerateConstraint)] = 1;
    by_reason[msgs::reasonIndex(InputRejection::kCountOverCapacity)] = 1;
    by_reason[msgs::reasonIndex(InputRejection::kBadNormal)] = 1;
    EXPECT_THAT(status.sim_link.rejected_by_reason, Eq(by_reason));
    EXPECT_THAT(status.sim_link.received, Eq(0U));
    EXPECT_FALSE(status.sim_link.connected);
}

// A sim from another release (over iceoryx, its twin in shared memory; over DDS the link
// hands such a message on for its header): the header's schema is checked first, since in
// another layout every other field means something else, and a sim that sends only such
// messages fades the force out as a silent one.
TEST_F(DaemonCoreTest, RefusesInputOfAnotherSchemaFirst) {
    std::int64_t t = 0;
    for (int i = 0; i < 200; ++i) {  // a sim of this release: full force
        (void)sut.offerConstraintSet(0, validConstraintSet("exo_index", t), t);
        t = runTicks(t, 1);
    }
    ASSERT_EQ(sut.simFade(0), 1.0);
    // Then a sim of the release before the field, whose header began with seq (1, 2, ...).
    for (int i = 0; i < 30; ++i) {
        auto constraints = validConstraintSet("exo_index", t);
        constraints.header.schema = static_cast<std::uint32_t>(i + 1);
        constraints.dof = 7;  // what another layout might put here: not the reason given
        EXPECT_THAT(sut.offerConstraintSet(0, constraints, t), Eq(InputRejection::kOtherSchema));
        t = runTicks(t, 1);
    }
    EXPECT_THAT(sut.simFade(0), Eq(0.0)) << "the refused input kept the force";
    auto surface = validContactSurface("thimble_index");
    surface.header.schema = msgs::kSchema + 1;
    EXPECT_THAT(sut.offerContactSurface(1, surface, t), Eq(InputRejection::kOtherSchema));
    EXPECT_THAT(sut.rejectedCount(0, InputRejection::kOtherSchema), Eq(30U));
    EXPECT_THAT(sut.rejectedCount(1, InputRejection::kOtherSchema), Eq(1U));
    EXPECT_EQ(daemon::describe(InputRejection::kOtherSchema),
              "header.schema is not this build's (a sim from another release)");
    EXPECT_STREQ(msgs::toString(InputRejection::kOtherSchema), "other_schema");
}

// A sample's normal follows the same length rule as a row's contact (docs/hapticd.md).
TEST_F(DaemonCoreTest, TakesASampleNormalWithinTheLengthRuleOnly) {
    auto long_normal = validContactSurface("thimble_index");
    long_normal.samples[0].normal_device = {0.0, 0.0, 1.0011};
    EXPECT_THAT(sut.offerContactSurface(1, long_normal, 0), Eq(InputRejection::kBadNormal));
    auto nearly_unit = validContactSurface("thimble_index");
    nearly_unit.samples[0].normal_device = {0.0, 0.0, 1.0009};
    EXPECT_THAT(sut.offerContactSurface(1, nearly_unit, 0), Eq(InputRejection::kNone));
}

// The contact behind a constraint row (msgs::ContactKinematics) is checked like the row.
TEST_F(DaemonCoreTest, RejectsABadContactBehindAConstraintRow) {
    auto withContact = [] {
        auto set = validConstraintSet("exo_index");
        msgs::ContactKinematics& c = set.constraints[0].contact;
        c.joints = 3;
        c.gap_m = -0.001;
        c.normal = {0.0, 0.0, 1.0};
        for (std::size_t j = 0; j < 3; ++j) {
            c.axis[j] = {0.0, 1.0, 0.0};
            c.lever_m[j] = {0.02, 0.0, -0.01};
        }
        return set;
    };
    EXPECT_THAT(sut.offerConstraintSet(0, withContact(), 0), Eq(InputRejection::kNone));
    auto nan_lever = withContact();
    nan_lever.constraints[0].contact.lever_m[2][1] = std::nan("");
    EXPECT_THAT(sut.offerConstraintSet(0, nan_lever, 0), Eq(InputRejection::kNonFinite));
    auto too_many_joints = withContact();
    too_many_joints.constraints[0].contact.joints = 4;  // the exoskeleton has 3
    EXPECT_THAT(sut.offerConstraintSet(0, too_many_joints, 0),
                Eq(InputRejection::kCountOverCapacity));
    auto negative_joints = withContact();
    negative_joints.constraints[0].contact.joints = -2;
    EXPECT_THAT(sut.offerConstraintSet(0, negative_joints, 0),
                Eq(InputRejection::kCountOverCapacity));
    auto long_axis = withContact();
    long_axis.constraints[0].contact.axis[1] = {0.0, 2.0, 0.0};
    EXPECT_THAT(sut.offerConstraintSet(0, long_axis, 0), Eq(InputRejection::kBadNormal));
    auto zero_normal = withContact();
    zero_normal.constraints[0].contact.normal = {0.0, 0.0, 0.0};
    EXPECT_THAT(sut.offerConstraintSet(0, zero_normal, 0), Eq(InputRejection::kBadNormal));
    // One length rule for every direction (docs/hapticd.md): within 1e-3 of 1 passes.
    auto nearly_unit_axis = withContact();
    nearly_unit_axis.constraints[0].contact.axis[1] = {0.0, 1.0009, 0.0};
    EXPECT_THAT(sut.offerConstraintSet(0, nearly_unit_axis, 0), Eq(InputRejection::kNone));
    auto short_normal = withContact();
    short_normal.constraints[0].contact.normal = {0.0, 0.0, 0.9989};
    EXPECT_THAT(sut.offerConstraintSet(0, short_normal, 0), Eq(InputRejection::kBadNormal));
    auto far_lever = withContact();
    far_lever.constraints[0].contact.lever_m[0] = {1e300, 0.0, 0.0};  // finite, no hand
    EXPECT_THAT(sut.offerConstraintSet(0, far_lever, 0), Eq(InputRejection::kDegenerateConstraint));
    // Unused slots must be finite too: a NaN there makes every frame differ from the last.
    auto nan_unused_slot = withContact();
    nan_unused_slot.constraints[0].contact.axis[3][0] = std::nan("");
    EXPECT_THAT(sut.offerConstraintSet(0, nan_unused_slot, 0), Eq(InputRejection::kNonFinite));
    auto nan_unused_a = withContact();
    nan_unused_a.constraints[0].a[7] = std::nan("");
    EXPECT_THAT(sut.offerConstraintSet(0, nan_unused_a, 0), Eq(InputRejection::kNonFinite));
}

TEST_F(DaemonCoreTest, StatusReportsDevicesLinkRateAndLoopWindow) {
    std::int64_t t = 0;
    for (int i = 0; i < 1000; ++i) {
        if (i % 10 == 0) {
            (void)sut.offerConstraintSet(0, validConstraintSet("exo_index", t), t);
        }
        t = runTicks(t, 1);
    }
    msgs::HapticStatus status;
    ASSERT_TRUE(sut.snapshotDue(t));
    sut.fillStatus(t, status);
    EXPECT_THAT(status.state, Eq(msgs::DaemonState::kIdle));
    ASSERT_THAT(status.devices.size(), Eq(2U));
    EXPECT_THAT(status.devices[0].device_id.view(), Eq("exo_index"));
    EXPECT_THAT(status.devices[1].kind, Eq(msgs::DeviceKind::kThimble));
    EXPECT_TRUE(status.sim_link.connected);
    EXPECT_THAT(status.sim_link.rate_hz, DoubleNear(100.0, 1.0));
    EXPECT_THAT(status.loop.ticks, Eq(1000U));
    EXPECT_THAT(status.loop.period_us.p50, DoubleNear(1000.0, 1.0));
    EXPECT_THAT(status.loop.overruns, Eq(0U));
    EXPECT_THAT(status.rendering_method.view(), Eq("subspace"));
}

// The fade starts at 15 ms of the 20 ms timeout: a 100 Hz sim never reaches it, a 60 Hz sim
// (a message every 17 ms) reaches it before every message, and status counts those ticks.
TEST_F(DaemonCoreTest, StatusCountsTicksOnWhichASlowSimLetTheInputAgePastTheFadeStart) {
    const auto run = [this](std::int64_t from, int interval_ms, int ticks) {
        std::int64_t t = from;
        for (int i = 0; i < ticks; ++i) {
            if (i % interval_ms == 0) {
                (void)sut.offerConstraintSet(0, validConstraintSet("exo_index", t), t);
                (void)sut.offerContactSurface(1, validContactSurface("thimble_index", t), t);
            }
            t = runTicks(t, 1);
        }
        return t;
    };
    msgs::HapticStatus status;
    std::int64_t t = run(0, 10, 1000);
    sut.fillStatus(t, status);
    EXPECT_THAT(status.sim_link.late_input_ticks, Eq(0U)) << "100 Hz is inside the fade start";
    EXPECT_THAT(sut.simFade(0), Eq(1.0));

    t = run(t, 17, 17 * 60);
    sut.fillStatus(t, status);
    // The ticks see ages 1..17 ms of each message; 16 and 17 are past the fade start.
    EXPECT_THAT(status.sim_link.late_input_ticks, Eq(2U * 60U));
    EXPECT_TRUE(status.sim_link.connected) << "late, not lost";
}

TEST_F(DaemonCoreTest, ForceGainFollowsTheFadeOnlyWhileRendering) {
    std::int64_t t = 0;
    for (int i = 0; i < 200; ++i) {
        (void)sut.offerConstraintSet(0, validConstraintSet("exo_index", t), t);
        t = runTicks(t, 1);
    }
    ASSERT_THAT(sut.simFade(0), Eq(1.0));
    EXPECT_THAT(sut.outputGain(0), Eq(0.0)) << "IDLE renders nothing";

    msgs::HapticCommand command;
    msgs::HapticCommandReply reply;
    command.kind = msgs::CommandKind::kEnable;
    ASSERT_TRUE(sut.applyCommand(command, t, reply).accepted);
    // An enable fades in as a sim that comes back does: from 0, never a step (it jumped to 1).
    EXPECT_THAT(sut.outputGain(0), Eq(0.0));
    double previous = 0.0;
    int ticks = 0;
    while (sut.outputGain(0) < 1.0 && ticks < 1000) {
        (void)sut.offerConstraintSet(0, validConstraintSet("exo_index", t), t);
        t = runTicks(t, 1);
        ++ticks;
        EXPECT_LE(sut.outputGain(0) - previous, 0.01 + 1e-12) << "tick " << ticks;
        previous = sut.outputGain(0);
    }
    EXPECT_THAT(sut.outputGain(0), Eq(1.0));
    EXPECT_NEAR(ticks, 100, 1) << "over loop.fade_in_ms";
    // A disable and an enable taken in the same tick fade in afresh too.
    command.kind = msgs::CommandKind::kDisable;
    ASSERT_TRUE(sut.applyCommand(command, t, reply).accepted);
    command.kind = msgs::CommandKind::kEnable;
    ASSERT_TRUE(sut.applyCommand(command, t, reply).accepted);
    EXPECT_THAT(sut.outputGain(0), Eq(0.0));
    (void)sut.offerConstraintSet(0, validConstraintSet("exo_index", t), t);
    t = runTicks(t, 1);
    EXPECT_NEAR(sut.outputGain(0), 0.01, 1e-12);
    command.kind = msgs::CommandKind::kEstop;
    ASSERT_TRUE(sut.applyCommand(command, t, reply).accepted);
    EXPECT_THAT(sut.outputGain(0), Eq(0.0)) << "E-STOP drops force at once";
}

TEST_F(DaemonCoreTest, TicksDoNotAllocate) {
    const auto constraint_set = validConstraintSet("exo_index");
    const auto contact_surface = validContactSurface("thimble_index");
    msgs::DeviceState state;
    msgs::HapticStatus status;
    std::int64_t t = 0;
    testing::ScopedAllocationCounter counter;
    for (int i = 0; i < 5000; ++i) {
        (void)sut.offerConstraintSet(0, constraint_set, t);
        (void)sut.offerContactSurface(1, contact_surface, t);
        t = runTicks(t, 1);
        sut.fillDeviceState(0, t, state);
        sut.fillDeviceState(1, t, state);
        if (sut.snapshotDue(t)) {
            sut.fillStatus(t, status);
        }
    }
    EXPECT_THAT(counter.allocations(), Eq(0U));
    EXPECT_THAT(status.header.seq, Gt(50U));
}

TEST(LoopStatistics, OverrunCauseIsTheLargestShare) {
    LoopStatisticsCollector sut(1000.0);
    sut.add(TickTiming{0, 1000, 900, 50, 100});   // 1050 us, read dominates
    sut.add(TickTiming{0, 1000, 10, 1200, 100});  // compute dominates
    sut.add(TickTiming{0, 1000, 10, 20, 1500});   // write dominates
    sut.add(TickTiming{0, 1000, 10, 20, 30});     // within budget
    msgs::LoopStatistics out;
    sut.closeWindow(out);
    EXPECT_THAT(out.overruns, Eq(3U));
    EXPECT_THAT(out.overruns_read, Eq(1U));
    EXPECT_THAT(out.overruns_compute, Eq(1U));
    EXPECT_THAT(out.overruns_write, Eq(1U));
}

TEST(MicrosecondHistogram, PercentilesBracketTheSamples) {
    MicrosecondHistogram sut;
    for (int i = 1; i <= 1000; ++i) {
        sut.add(static_cast<double>(i) * 0.999);
    }
    sut.add(12000.0);  // past the last bin: only max sees it exactly
    const auto p = percentilesOf(sut);
    EXPECT_THAT(p.p50, DoubleNear(500.0, 1.5));
    EXPECT_THAT(p.p99, DoubleNear(990.0, 2.0));
    EXPECT_THAT(p.max, Eq(12000.0));
}

}  // namespace
}  // namespace haptic::daemon
