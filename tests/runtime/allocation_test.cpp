// hapticd's full per-tick path (both devices, real drivers, renderers, safety stages and
// DaemonCore, the emulators answering on the loopback bus) must not touch the heap after
// start.

#include <gtest/gtest.h>

#include <string>

#include "allocation_counter.hpp"
#include "haptic/runtime/exoskeleton_channel.hpp"
#include "runtime_rig.hpp"

namespace haptic::testing {
namespace {

TEST(RuntimeAllocation, TenThousandTicksOfBothDevicesAllocateNothing) {
    // With every optional stage of the tick on: the user-stiffness estimate too.
    RuntimeRig rig([](std::vector<config::DeviceConfig>& devices) {
        std::get<config::ExoskeletonConfig>(devices[kExo].params)
            .rendering.user_stiffness_estimate.enabled = true;
    });
    rig.attachEstopRelay();  // its frames, supervision and a press are on the path too
    rig.offerContact();
    rig.ticks(20);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    rig.ticks(5);

    std::uint64_t allocations = 0;
    double peak_force = 0.0;
    bool saw_estop = false;
    {
        ScopedAllocationCounter counter;
        for (int i = 0; i < 10'000; ++i) {
            if (i % 10 == 0) {
                rig.offerContact();  // a 100 Hz sim
            }
            if (i == 5'000) {
                (void)rig.command(msgs::CommandKind::kDisable);
                (void)rig.command(msgs::CommandKind::kSetMethod, "anisotropic");
                (void)rig.command(msgs::CommandKind::kEnable);
            }
            std::string unused;
            if (i == 8'000) {
                (void)rig.estop_relay->command("press", unused);
            }
            if (i == 8'100) {
                (void)rig.estop_relay->command("release", unused);
            }
            if (i == 8'200) {
                (void)rig.command(msgs::CommandKind::kClearFault);
                (void)rig.command(msgs::CommandKind::kEnable);
            }
            rig.tick();
            saw_estop = saw_estop || rig.core.state() == msgs::DaemonState::kEstop;
            peak_force = std::max(peak_force, std::abs(rig.exoForce()));
        }
        allocations = counter.allocations();
    }
    EXPECT_EQ(allocations, 0U);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kRendering);
    EXPECT_TRUE(saw_estop) << "the relay's press must have stopped the loop";
    EXPECT_EQ(rig.core.stateMachine().faultCount(), 0U) << "and been cleared";
    EXPECT_GT(peak_force, 1.0) << "the loop must have rendered force, not idled";
    EXPECT_GT(rig.core.deviceReport(kExo).can.rx_frames, 10'000U);
    const auto& exo = static_cast<runtime::ExoskeletonChannel&>(rig.runtime.channel(kExo));
    ASSERT_NE(exo.userStiffnessEstimator(), nullptr);
    EXPECT_GT(exo.userStiffnessEstimator()->contactTime(), 0.5) << "the estimator ran";
}

}  // namespace
}  // namespace haptic::testing
