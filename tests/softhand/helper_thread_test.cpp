// The soft-hand step's helper thread (sim/softhand/include/haptic/softhand/helper_thread.hpp):
// it hands jobs over and back without losing or repeating one, and a step that uses it is the
// step without it, to the bit, on the scenes where the helper does the most (restarted solves,
// line searches with many halvings, two Newton iterations). Label `threaded`: run under TSan.

#include "haptic/softhand/helper_thread.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <thread>

#include "finger_flex_scene.hpp"
#include "fingertip_press_scene.hpp"
#include "haptic/config/scene.hpp"
#include "haptic/softhand/scene_simulation.hpp"

namespace haptic::softhand {
namespace {

struct Counter {
    int value{0};  // written by the helper only, read by the test after wait() or withdraw()
};

void increment(void* context) {
    ++static_cast<Counter*>(context)->value;
}

TEST(HelperThread, RunsEachJobItKeepsOnceAndHandsItsResultBack) {
    HelperThread helper;
    EXPECT_TRUE(helper.done()) << "no job yet";
    helper.wait();  // no job: returns at once
    EXPECT_FALSE(helper.withdraw()) << "no job to take back";
    Counter counter;
    for (int i = 0; i < 2000; ++i) {
        helper.start(increment, &counter);
        helper.wait();
        ASSERT_EQ(counter.value, i + 1);
        EXPECT_TRUE(helper.done());
        // Counted by the helper itself, once per job it ran; a wake-up runs none.
        ASSERT_EQ(helper.jobsRun(), static_cast<std::uint64_t>(i + 1));
        helper.wake();
        helper.wait();
        ASSERT_EQ(helper.jobsRun(), static_cast<std::uint64_t>(i + 1)) << "a wake() counted";
    }
    // A job taken back never runs; one that is not taken back has run when withdraw returns.
    int expected = counter.value;
    int taken_back = 0;
    for (int i = 0; i < 2000; ++i) {
        helper.start(increment, &counter);
        if (helper.withdraw()) {
            ++taken_back;
        } else {
            ++expected;
        }
        ASSERT_EQ(counter.value, expected) << "job " << i;
        ASSERT_EQ(helper.jobsRun(), static_cast<std::uint64_t>(expected))
            << "a job taken back counted, job " << i;
    }
    // start() takes back or waits for the job before it: every job runs at most once.
    for (int i = 0; i < 100; ++i) {
        helper.start(increment, &counter);
    }
    helper.wait();
    EXPECT_GT(counter.value, expected);
    EXPECT_LE(counter.value, expected + 100);
    EXPECT_EQ(helper.jobsRun(), static_cast<std::uint64_t>(counter.value));
    std::printf("%d of 2000 jobs taken back before they began\n", taken_back);
}

TEST(HelperThread, ItsDestructorWaitsForTheJobUnderWay) {
    struct Slow {
        std::atomic<bool> began{false};
        std::atomic<bool> finished{false};
    } slow;
    {
        HelperThread helper;
        helper.start(
            [](void* context) {
                auto& job = *static_cast<Slow*>(context);
                job.began.store(true);
                volatile double sink = 0.0;
                for (int i = 0; i < 2'000'000; ++i) {
                    sink = sink + 1.0;
                }
                job.finished.store(true);
            },
            &slow);
        while (!slow.began.load()) {
        }
    }
    EXPECT_TRUE(slow.finished.load());
}

bool sameBits(const Vec3& a, const Vec3& b) {
    return std::memcmp(a.data(), b.data(), sizeof(double) * 3) == 0;
}

// Steps two copies of a scene, one with the helper thread, and asserts that every node and
// body, and what the solver reports, are identical after every step.
template <typename Scene>
void expectTheSameSteps(int level, const std::optional<config::SolverLimits>& limits, int steps,
                        const char* what) {
    const int cap = limits ? limits->pcg_max_iterations : 30;
    Scene alone(level, cap, 1e-4);
    Scene helped(level, cap, 1e-4);
    if (limits) {
        alone.solver() = withRealtimeLimits(alone.solver(), *limits);
        helped.solver() = withRealtimeLimits(helped.solver(), *limits);
    }
    alone.solver().use_helper_thread = false;
    helped.solver().use_helper_thread = true;
    int restarted = 0;
    int backtracks = 0;
    int substeps = 0;
    int newton = 0;
    int helper_jobs = 0;
    int helper_results = 0;
    for (int step = 0; step < steps; ++step) {
        alone.setInput(step);
        helped.setInput(step);
        const StepReport a = alone.step();
        const StepReport b = helped.step();
        ASSERT_EQ(a.pcg_iterations, b.pcg_iterations) << what << " step " << step;
        ASSERT_EQ(a.backtracks, b.backtracks) << what << " step " << step;
        ASSERT_EQ(a.restarted_solves, b.restarted_solves) << what << " step " << step;
        ASSERT_EQ(a.newton_iterations, b.newton_iterations) << what << " step " << step;
        ASSERT_EQ(a.rescaled_steps, b.rescaled_steps) << what << " step " << step;
        ASSERT_EQ(a.substeps, b.substeps) << what << " step " << step;
        const Simulation& x = alone.simulation();
        const Simulation& y = helped.simulation();
        for (int node = 0; node < x.nodeCount(); ++node) {
            ASSERT_TRUE(sameBits(x.nodePosition(node), y.nodePosition(node)) &&
                        sameBits(x.nodeVelocity(node), y.nodeVelocity(node)))
                << what << " step " << step << " node " << node;
        }
        for (int body = 0; body < x.bodyCount(); ++body) {
            ASSERT_TRUE(sameBits(x.bodyPosition(body), y.bodyPosition(body)) &&
                        sameBits(x.bodyLinearVelocity(body), y.bodyLinearVelocity(body)))
                << what << " step " << step << " body " << body;
        }
        ASSERT_EQ(a.helper_jobs, 0) << what << " step " << step;
        ASSERT_LE(b.helper_results_used, b.helper_jobs) << what << " step " << step;
        helper_jobs += b.helper_jobs;
        if (b.substeps == 1) {  // a step split into substeps discarded its first attempt
            helper_results += b.helper_results_used;
        }
        restarted += a.restarted_solves;
        backtracks += a.backtracks;
        substeps += a.substeps - 1;
        newton += a.newton_iterations;
    }
    // The paths the helper serves ran: cold solves it had ready, and halvings it evaluated
    // (and, at the library's defaults, further Newton iterations and substeps). And the helper
    // ran some of those jobs itself, and the steps' attempts used their results: were every job
    // taken back, or every result it computed left unused, the steps would be the same to the
    // bit without proving anything. Counted on steps taken whole (one substep) only.
    EXPECT_GT(helper_jobs, 0) << what;
    EXPECT_GT(helper_results, 0) << what;
    if (limits) {
        EXPECT_GT(restarted, 0) << what;
        EXPECT_GT(backtracks, 2 * restarted) << what;
    } else {
        EXPECT_GT(newton, steps / 4) << what;
        EXPECT_GT(backtracks, 0) << what;
    }
    std::printf(
        "%s: %d steps, %d restarted solves, %d halvings, %d Newton iterations beyond "
        "the first, %d extra substeps; %d jobs run on the helper, %d of their results used\n",
        what, steps, restarted, backtracks, newton, substeps, helper_jobs, helper_results);
}

TEST(HelperThread, HandsimUsesItWhereTheSceneAllowsAndASecondCoreExists) {
    config::SolverLimits limits;
    EXPECT_FALSE(withRealtimeLimits(SolverSettings{}, limits).use_helper_thread);
    EXPECT_FALSE(realtimeSceneSettings(limits).solver.use_helper_thread);
    limits.helper_thread = true;  // scene YAML solver.helper_thread: true
    EXPECT_EQ(withRealtimeLimits(SolverSettings{}, limits).use_helper_thread, usableCores() >= 2);
    EXPECT_GE(usableCores(), 1);
    EXPECT_LE(usableCores(), static_cast<int>(std::thread::hardware_concurrency()));
    EXPECT_FALSE(SolverSettings{}.use_helper_thread) << "the library's default: one thread";
}

TEST(HelperThread, TheThimbleScenesStepsAreTheSameToTheBit) {
    // The thimble scene's point (level 1, 1 Newton iteration, cap 30, the helper on): its
    // slowest steps are a restarted solve with 6-8 halvings. 120 steps press, slide and lift.
    const config::SolverLimits limits =
        config::loadSceneConfig(std::string(HAPTIC_SOURCE_DIR) + "/config/scenes/thimble_only.yaml")
            .solver;
    expectTheSameSteps<bench::FingertipPress>(1, limits, 120, "fingertip press");
}

TEST(HelperThread, TwoNewtonIterationsStepTheSameToTheBit) {
    // The default scene's budget (2 Newton iterations): the helper's jobs are collected
    // before the second iteration assembles.
    const config::SolverLimits limits =
        config::loadSceneConfig(std::string(HAPTIC_SOURCE_DIR) + "/config/scenes/default.yaml")
            .solver;
    ASSERT_EQ(limits.newton_iterations, 2);
    expectTheSameSteps<bench::FingerFlex>(0, limits, 120, "finger flex");
}

TEST(HelperThread, TheLibrarysDefaultSettingsStepTheSameToTheBit) {
    // 5 Newton iterations to a tolerance, 10 halvings, energy substeps allowed: the helper's
    // jobs withdrawn before each further iteration and at the convergence exit (this scene
    // needs no substep: 128 further iterations, 647 halvings, 0 substeps in 200 steps).
    expectTheSameSteps<bench::FingertipPress>(0, std::nullopt, 200, "fingertip press, defaults");
}

}  // namespace
}  // namespace haptic::softhand
