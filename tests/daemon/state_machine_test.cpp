// The daemon state machine (state_machine.hpp) through its public API, the command path
// through DaemonCore, and the lock-free command channel hapticd uses between its threads.

#include "haptic/daemon/state_machine.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <thread>

#include "allocation_counter.hpp"
#include "haptic/daemon/command_channel.hpp"
#include "haptic/daemon/daemon_core.hpp"

namespace haptic::daemon {
namespace {

using msgs::CommandKind;
using msgs::DaemonState;
using ::testing::Eq;
using ::testing::HasSubstr;

DaemonStateMachine runningMachine() {
    DaemonStateMachine machine({"subspace", "naive", "linearized_subspace"}, "subspace");
    machine.started();
    return machine;
}

TEST(DaemonStateMachine, StartsInInitAndRefusesCommandsUntilStarted) {
    DaemonStateMachine machine({"subspace"}, "subspace");
    EXPECT_THAT(machine.state(), Eq(DaemonState::kInit));
    const auto outcome = machine.apply(CommandKind::kEnable, "");
    EXPECT_FALSE(outcome.accepted);
    EXPECT_THAT(outcome.reason, HasSubstr("initialising"));
    EXPECT_THAT(machine.state(), Eq(DaemonState::kInit));
    machine.started();
    EXPECT_THAT(machine.state(), Eq(DaemonState::kIdle));
    EXPECT_FALSE(machine.rendering());
}

TEST(DaemonStateMachine, EnableAndDisableToggleRendering) {
    auto machine = runningMachine();
    EXPECT_TRUE(machine.apply(CommandKind::kEnable, "").accepted);
    EXPECT_THAT(machine.state(), Eq(DaemonState::kRendering));
    EXPECT_TRUE(machine.rendering());
    EXPECT_TRUE(machine.apply(CommandKind::kEnable, "").accepted) << "idempotent";
    EXPECT_TRUE(machine.apply(CommandKind::kDisable, "").accepted);
    EXPECT_THAT(machine.state(), Eq(DaemonState::kIdle));
    EXPECT_TRUE(machine.apply(CommandKind::kDisable, "").accepted) << "idempotent";
    EXPECT_THAT(machine.state(), Eq(DaemonState::kIdle));
}

TEST(DaemonStateMachine, ClearWithNothingToClearIsRefused) {
    auto machine = runningMachine();
    const auto outcome = machine.apply(CommandKind::kClearFault, "");
    EXPECT_FALSE(outcome.accepted);
    EXPECT_THAT(outcome.reason, HasSubstr("nothing to clear"));
    EXPECT_THAT(machine.state(), Eq(DaemonState::kIdle));
}

TEST(DaemonStateMachine, EstopFromEveryRunningStateHoldsUntilClearThenIdle) {
    for (const auto setup : {0, 1, 2}) {
        auto machine = runningMachine();
        if (setup == 1) {
            ASSERT_TRUE(machine.apply(CommandKind::kEnable, "").accepted);
        } else if (setup == 2) {
            machine.raiseFault(7, "exo", "heartbeat lost");
        }
        EXPECT_TRUE(machine.apply(CommandKind::kEstop, "").accepted) << setup;
        EXPECT_THAT(machine.state(), Eq(DaemonState::kEstop));
        EXPECT_TRUE(machine.apply(CommandKind::kEstop, "").accepted) << "idempotent";

        const auto enable = machine.apply(CommandKind::kEnable, "");
        EXPECT_FALSE(enable.accepted);
        EXPECT_THAT(enable.reason, HasSubstr("emergency stop"));
        EXPECT_FALSE(machine.apply(CommandKind::kDisable, "").accepted);
        EXPECT_FALSE(machine.apply(CommandKind::kSetMethod, "naive").accepted);
        // A fault during E-STOP is listed but does not leave E-STOP.
        machine.raiseFault(9, "thimble", "bus off");
        EXPECT_THAT(machine.state(), Eq(DaemonState::kEstop));

        EXPECT_TRUE(machine.apply(CommandKind::kClearFault, "").accepted);
        EXPECT_THAT(machine.state(), Eq(DaemonState::kIdle)) << "clear never resumes rendering";
        EXPECT_THAT(machine.faultCount(), Eq(0U));
    }
}

TEST(DaemonStateMachine, FaultIsLatchedUntilClearedAndListed) {
    auto machine = runningMachine();
    ASSERT_TRUE(machine.apply(CommandKind::kEnable, "").accepted);
    machine.raiseFault(3, "exo", "heartbeat lost");
    EXPECT_THAT(machine.state(), Eq(DaemonState::kFault));
    EXPECT_FALSE(machine.rendering());
    ASSERT_THAT(machine.faultCount(), Eq(1U));
    EXPECT_THAT(machine.fault(0).code, Eq(3U));
    EXPECT_THAT(machine.fault(0).device_id.view(), Eq("exo"));
    EXPECT_THAT(machine.fault(0).message.view(), Eq("heartbeat lost"));

    const auto enable = machine.apply(CommandKind::kEnable, "");
    EXPECT_FALSE(enable.accepted);
    EXPECT_THAT(enable.reason, HasSubstr("fault is latched"));
    EXPECT_FALSE(machine.apply(CommandKind::kDisable, "").accepted);
    EXPECT_THAT(machine.state(), Eq(DaemonState::kFault)) << "latched";

    EXPECT_TRUE(machine.apply(CommandKind::kClearFault, "").accepted);
    EXPECT_THAT(machine.state(), Eq(DaemonState::kIdle));
    EXPECT_THAT(machine.faultCount(), Eq(0U));
}

TEST(DaemonStateMachine, FaultListKeepsTheFirstEntriesAndCountsTheRest) {
    auto machine = runningMachine();
    for (std::uint32_t i = 0; i < DaemonStateMachine::kMaxFaults + 3; ++i) {
        machine.raiseFault(i, "exo", "x");
    }
    EXPECT_THAT(machine.faultCount(), Eq(DaemonStateMachine::kMaxFaults));
    EXPECT_THAT(machine.droppedFaults(), Eq(3U));
    EXPECT_THAT(machine.fault(0).code, Eq(0U));
}

TEST(DaemonStateMachine, MethodChangesInIdleOrRenderingAndOnlyToAKnownMethod) {
    auto machine = runningMachine();
    const auto unknown = machine.apply(CommandKind::kSetMethod, "magic");
    EXPECT_FALSE(unknown.accepted);
    EXPECT_THAT(unknown.reason, HasSubstr("unknown rendering method"));
    EXPECT_THAT(machine.method().view(), Eq("subspace"));

    EXPECT_TRUE(machine.apply(CommandKind::kSetMethod, "naive").accepted);
    EXPECT_THAT(machine.method().view(), Eq("naive"));

    // Live while RENDERING: the exoskeleton's channel blends into it within the rate limit.
    ASSERT_TRUE(machine.apply(CommandKind::kEnable, "").accepted);
    EXPECT_TRUE(machine.apply(CommandKind::kSetMethod, "linearized_subspace").accepted);
    EXPECT_THAT(machine.method().view(), Eq("linearized_subspace"));
    EXPECT_EQ(machine.state(), DaemonState::kRendering);

    ASSERT_TRUE(machine.apply(CommandKind::kEstop, "").accepted);
    const auto while_stopped = machine.apply(CommandKind::kSetMethod, "naive");
    EXPECT_FALSE(while_stopped.accepted);
    EXPECT_THAT(while_stopped.reason, HasSubstr("only in IDLE or RENDERING"));
    EXPECT_THAT(machine.method().view(), Eq("linearized_subspace"));
}

TEST(DaemonStateMachine, NamesMatchTheStatusScreen) {
    EXPECT_STREQ(toString(DaemonState::kEstop), "E-STOP");
    EXPECT_STREQ(toString(DaemonState::kRendering), "RENDERING");
}

DaemonCore makeCore() {
    CoreSettings settings;
    settings.rendering_method = "subspace";
    settings.known_methods = {"subspace", "naive"};
    DaemonCore core(settings, {DeviceDescriptor{"exo", msgs::DeviceKind::kExoskeleton, 3, 1}});
    core.markStarted(0);
    return core;
}

msgs::HapticCommand command(CommandKind kind, std::uint64_t request_id,
                            std::string_view argument = "") {
    msgs::HapticCommand out;
    out.kind = kind;
    out.request_id = request_id;
    out.argument.assign(argument);
    return out;
}

TEST(DaemonCoreCommands, ReplyCarriesRequestIdOutcomeAndStatusShowsStateMethodAndFaults) {
    auto core = makeCore();
    msgs::HapticCommandReply reply;
    core.applyCommand(command(CommandKind::kSetMethod, 41, "naive"), 5, reply);
    EXPECT_THAT(reply.request_id, Eq(41U));
    EXPECT_TRUE(reply.accepted);
    core.applyCommand(command(CommandKind::kClearFault, 42), 6, reply);
    EXPECT_THAT(reply.request_id, Eq(42U));
    EXPECT_FALSE(reply.accepted);
    EXPECT_THAT(std::string(reply.message.view()), HasSubstr("nothing to clear"));

    core.applyCommand(command(CommandKind::kEnable, 43), 7, reply);
    EXPECT_THAT(core.state(), Eq(DaemonState::kRendering));
    core.raiseFault(5, "exo", "bus off");
    msgs::HapticStatus status;
    core.fillStatus(8, status);
    EXPECT_THAT(status.state, Eq(DaemonState::kFault));
    EXPECT_THAT(status.rendering_method.view(), Eq("naive"));
    ASSERT_THAT(status.faults.size(), Eq(1U));
    EXPECT_THAT(status.faults[0].message.view(), Eq("bus off"));
}

TEST(CommandChannel, CommandsAndRepliesCrossThreadsInOrderWithoutAllocating) {
    CommandChannel channel;
    auto core = makeCore();
    constexpr std::uint64_t kCommands = 500;
    std::thread rt([&] {
        testing::ScopedAllocationCounter counter;
        std::uint64_t handled = 0;
        msgs::HapticCommand incoming;
        msgs::HapticCommandReply reply;
        while (handled < kCommands) {
            while (channel.takeCommand(incoming)) {
                core.applyCommand(incoming, 0, reply);
                while (!channel.postReply(reply)) {
                    std::this_thread::yield();
                }
                ++handled;
            }
        }
        EXPECT_THAT(counter.allocations(), Eq(0U)) << "the RT side must not allocate";
    });
    std::uint64_t next_reply = 1;
    msgs::HapticCommandReply reply;
    for (std::uint64_t id = 1; id <= kCommands; ++id) {
        const auto kind = id % 2 == 1 ? CommandKind::kEnable : CommandKind::kDisable;
        while (!channel.submit(command(kind, id))) {
            std::this_thread::yield();
        }
        while (channel.takeReply(reply)) {
            EXPECT_THAT(reply.request_id, Eq(next_reply++));
            EXPECT_TRUE(reply.accepted);
        }
    }
    // Keep reading replies until the last: the RT side waits for room to post each (up to 16
    // commands in flight plus the one it holds can exceed the reply queue), so joining first
    // could deadlock (it did under TSan).
    while (next_reply <= kCommands) {
        while (channel.takeReply(reply)) {
            EXPECT_THAT(reply.request_id, Eq(next_reply++));
        }
        std::this_thread::yield();
    }
    rt.join();
    EXPECT_FALSE(channel.takeReply(reply));
    EXPECT_THAT(core.state(), Eq(DaemonState::kIdle));
}

}  // namespace
}  // namespace haptic::daemon
