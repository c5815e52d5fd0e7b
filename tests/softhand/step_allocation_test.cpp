// The soft hand step allocates nothing once its buffers have grown: the Hessian pattern,
// PCG vectors, configurations and contact lists are kept between steps.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "allocation_counter.hpp"
#include "haptic/softhand/hand_builder.hpp"
#include "haptic/softhand/scene_simulation.hpp"

namespace haptic::softhand {
namespace {

constexpr double kDt = 0.005;
constexpr int kCycleSteps = 60;

// Press 4 mm into a table, slide, lift: contacts appear, stick, slide and vanish.
void setPressInput(Simulation& sim, int bone, const Vec3& start, int step) {
    const double t = static_cast<double>(step % kCycleSteps) / kCycleSteps;
    const double press = t < 0.2 ? t / 0.2 : (t < 0.8 ? 1.0 : (1.0 - t) / 0.2);
    const double slide = t < 0.2 ? 0.0 : std::min(1.0, (t - 0.2) / 0.6);
    sim.setTrackingTarget(bone, start + Vec3(0.008 * slide, 0.0, -0.005 * press), Mat3::Identity());
}

void expectNoAllocationAfterTheFirstCycle(bool realtime) {
    config::HandConfig hand;
    hand.model = config::HandModel::kFingertip;
    hand.resolution = 1;
    hand.anthropometry = {0.19, 0.085, 0.016};
    SolverSettings settings;
    settings.contact_stiffness_n_per_m = 3000.0;
    HandModel model = buildHand(hand, settings);
    Simulation& sim = model.simulation;
    if (realtime) {
        // handsim's budget, with the helper thread (whose buffers the step sizes).
        sim.settings() = withRealtimeLimits(sim.settings(), config::SolverLimits{});
        sim.settings().use_helper_thread = true;
    }
    sim.addCollider({HalfSpace{}, Vec3(0.0, 0.0, -0.009), Mat3::Identity(), 0.6});
    const int bone = model.bones.front().body;
    const Vec3 start = sim.bodyPosition(bone);

    int contact_steps = 0;
    int backtracking_steps = 0;
    for (int step = 0; step < kCycleSteps; ++step) {  // buffers grow here
        setPressInput(sim, bone, start, step);
        sim.step(kDt);
    }
    std::uint64_t allocations = 0;
    int helper_jobs = 0;
    for (int step = kCycleSteps; step < 2 * kCycleSteps; ++step) {
        setPressInput(sim, bone, start, step);
        StepReport report;
        {
            // Every thread's: the helper thread's jobs count too.
            const testing::ScopedProcessAllocationCounter counter;
            report = sim.step(kDt);
            allocations += counter.allocations();
        }
        helper_jobs += report.helper_jobs;
        contact_steps += report.active_contacts > 0 ? 1 : 0;
        backtracking_steps += report.backtracks > 0 || report.substepped ? 1 : 0;
        ASSERT_FALSE(report.rejected_input) << report.rejection_reason;
    }
    // The cycle really exercised contacts (and usually the energy check's backtracking), and
    // with the helper thread, jobs it ran.
    EXPECT_GT(contact_steps, kCycleSteps / 2);
    if (realtime) {
        EXPECT_GT(helper_jobs, 0) << "the helper thread ran no job: its allocations went unseen";
    }
    EXPECT_EQ(allocations, 0U) << "over " << kCycleSteps << " steps, " << contact_steps
                               << " with contacts, " << backtracking_steps
                               << " backtracking or substepping";
}

TEST(SofthandAllocation, StepAllocatesNothingAfterTheFirstCycle) {
    expectNoAllocationAfterTheFirstCycle(false);
}

TEST(SofthandAllocation, NorWithHandsimsLimitsAndTheHelperThread) {
    expectNoAllocationAfterTheFirstCycle(true);
}

}  // namespace
}  // namespace haptic::softhand
