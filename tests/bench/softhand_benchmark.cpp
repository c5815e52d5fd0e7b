// Step time and accuracy of the soft hand, per resolution level and PCG iteration cap.
//   ninja -C build/release softhand_benchmark && build/release/tests/bench/softhand_benchmark
// Scenes at 200 Hz (dt = 5 ms): a fingertip pressing 4 mm into a table and sliding 1 cm (the
// thimble scene), one finger flexing against a table (the exoskeleton scene), and the whole
// hand moved up and down by its tracking (no contact).
// Counters: p50_us / p99_us over the steps of the run; pcg_iters, backtracks, substeps,
// newton_extra (Newton iterations beyond the first), rescaled (steps whose energy rose with no
// substep left, velocities scaled down) and zeroed (steps held with no finite state) per step;
// force_err = RMS(F - F_ref) / RMS(F_ref) of the normal force on the table over the first second,
// press_err the same over its first 0.2 s (pressing in, no sliding yet: the fine reference
// stick-slips while sliding, which dominates force_err); tip_err_mm = RMS distance of the distal
// bone from the reference (flex). The reference is the same scene one resolution level finer than
// the finest row, with PCG to a relative tolerance of 1e-8 (up to 2000 iterations), computed once
// before the rows run.

#include <benchmark/benchmark.h>
#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "benchmark_runner.hpp"
#include "finger_flex_scene.hpp"
#include "fingertip_press_scene.hpp"
#include "haptic/common/statistics.hpp"
#include "haptic/config/scene.hpp"
#include "haptic/softhand/elastic_tracking.hpp"
#include "haptic/softhand/hand_builder.hpp"
#include "haptic/softhand/scene_simulation.hpp"
#include "thread_cpu_time.hpp"

namespace haptic::softhand {
namespace {

// The fingertip press scene, its constants and helpers are shared with the Bullet comparison.
using bench::FingerFlex;
using bench::FingertipPress;
using bench::handConfig;
using bench::kCycleSteps;
using bench::kDt;
using bench::kPressReferenceLevel;
using bench::kPressSteps;
using bench::Sample;
using bench::solverSettings;
using haptic::bench::processCpuUs;
using haptic::bench::threadCpuUs;
constexpr int kFlexReferenceLevel = 3;

// p50 and p99 of per-step times into the state's counters, with `prefix`.
void addPercentiles(benchmark::State& state, std::vector<double> us, const char* prefix) {
    state.counters[std::string(prefix) + "p50_us"] = common::percentile(us, 0.5);
    state.counters[std::string(prefix) + "p99_us"] = common::percentile(us, 0.99);
}

template <typename Scene>
const std::vector<Sample>& reference(int level) {
    static std::map<int, std::vector<Sample>> cache;
    auto found = cache.find(level);
    if (found == cache.end()) {
        Scene scene(level, 2000, 1e-8);
        std::vector<Sample> trace;
        for (int s = 0; s < kCycleSteps; ++s) {
            scene.setInput(s);
            scene.step();
            trace.push_back(scene.sample());
        }
        found = cache.emplace(level, std::move(trace)).first;
    }
    return found->second;
}

// How a row limits the solver's work per step beyond the PCG cap.
enum class StepLimits {
    kBenchmark,  // SolverSettings' defaults: 5 Newton iterations, 10 halvings, 8 substeps
    kHandsim,    // handsim's real-time limits, realtimeSceneSettings()
};

template <typename Scene>
void run(benchmark::State& state, int reference_level, StepLimits limits) {
    const std::vector<Sample>& ref = reference<Scene>(reference_level);
    Scene scene(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), 1e-4);
    if (limits == StepLimits::kHandsim) {
        config::SolverLimits budget;  // handsim's default Newton count, this row's PCG cap
        budget.pcg_max_iterations = static_cast<int>(state.range(1));
        scene.solver() = withRealtimeLimits(scene.solver(), budget);
        // Third argument: 1 = with the helper thread, as handsim runs, 0 = without.
        scene.solver().use_helper_thread = state.range(2) != 0;
    }
    std::vector<double> step_us;
    std::vector<double> cpu_us;
    double pcg_iterations = 0.0;
    double backtracks = 0.0;
    double substeps = 0.0;
    double newton = 0.0;
    double zeroed = 0.0;
    double rescaled = 0.0;
    double restarted = 0.0;
    double force_error2 = 0.0;
    double force_ref2 = 0.0;
    double tip_error2 = 0.0;
    double press_error2 = 0.0;
    double press_ref2 = 0.0;
    int step = 0;
    double process_cpu_us = 0.0;
    for (auto _ : state) {
        scene.setInput(step);
        const double c0 = threadCpuUs();
        const double p0 = processCpuUs();
        const auto t0 = std::chrono::steady_clock::now();
        const StepReport r = scene.step();
        const auto t1 = std::chrono::steady_clock::now();
        cpu_us.push_back(threadCpuUs() - c0);
        process_cpu_us += processCpuUs() - p0;
        step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        pcg_iterations += r.pcg_iterations;
        backtracks += r.backtracks;
        substeps += r.substeps;
        newton += r.newton_iterations;
        zeroed += r.zeroed_steps;
        rescaled += r.rescaled_steps;
        restarted += r.restarted_solves;
        if (step < kCycleSteps) {
            const Sample s = scene.sample();
            const Sample& expected = ref[static_cast<std::size_t>(step)];
            force_error2 += std::pow(s.table_force_n - expected.table_force_n, 2);
            force_ref2 += std::pow(expected.table_force_n, 2);
            tip_error2 += (s.tip_m - expected.tip_m).squaredNorm();
            if (step < kPressSteps) {
                press_error2 += std::pow(s.table_force_n - expected.table_force_n, 2);
                press_ref2 += std::pow(expected.table_force_n, 2);
            }
        }
        ++step;
        benchmark::DoNotOptimize(r.energy_j);
    }
    const auto steps = static_cast<double>(step_us.size());
    const double compared = std::min(steps, static_cast<double>(kCycleSteps));
    state.counters["nodes"] = scene.simulation().nodeCount();
    state.counters["tets"] = scene.simulation().tetCount();
    addPercentiles(state, step_us, "");
    addPercentiles(state, cpu_us, "cpu_");
    state.counters["process_cpu_mean_us"] = process_cpu_us / steps;
    state.counters["pcg_iters"] = pcg_iterations / steps;
    state.counters["backtracks"] = backtracks / steps;
    state.counters["substeps"] = substeps / steps;
    state.counters["newton_extra"] = newton / steps;
    state.counters["zeroed"] = zeroed / steps;
    state.counters["rescaled"] = rescaled / steps;
    state.counters["restarted"] = restarted / steps;
    state.counters["force_err"] = std::sqrt(force_error2 / std::max(force_ref2, 1e-30));
    state.counters["press_err"] = std::sqrt(press_error2 / std::max(press_ref2, 1e-30));
    state.counters["tip_err_mm"] = 1e3 * std::sqrt(tip_error2 / compared);
}

void fingertipPress(benchmark::State& state) {
    run<FingertipPress>(state, kPressReferenceLevel, StepLimits::kBenchmark);
}
void fingerFlex(benchmark::State& state) {
    run<FingerFlex>(state, kFlexReferenceLevel, StepLimits::kBenchmark);
}
// The same scenes under handsim's real-time limits (fewer halvings, one substep level): what
// the thimble scene costs in the running handsim.
void fingertipPressHandsimLimits(benchmark::State& state) {
    run<FingertipPress>(state, kPressReferenceLevel, StepLimits::kHandsim);
}
void fingerFlexHandsimLimits(benchmark::State& state) {
    run<FingerFlex>(state, kFlexReferenceLevel, StepLimits::kHandsim);
}

// Whole hand held by its tracking and moved 1 cm up and down once per second.
void wholeHand(benchmark::State& state) {
    HandModel model =
        buildHand(handConfig(config::HandModel::kHand, static_cast<int>(state.range(0))),
                  solverSettings(static_cast<int>(state.range(1)), 1e-4));
    std::vector<std::pair<Vec3, Mat3>> build;
    for (const auto& bone : model.bones) {
        build.emplace_back(model.simulation.bodyPosition(bone.body),
                           model.simulation.bodyRotation(bone.body));
    }
    std::vector<double> step_us;
    std::vector<double> cpu_us;
    double pcg_iterations = 0.0;
    double substeps = 0.0;
    double newton = 0.0;
    int step = 0;
    for (auto _ : state) {
        const double lift = 0.01 * std::sin(2.0 * 3.14159265 * (step++ % kCycleSteps) * kDt);
        for (std::size_t k = 0; k < build.size(); ++k) {
            model.simulation.setTrackingTarget(
                model.bones[k].body, build[k].first + Vec3(0.0, 0.0, lift), build[k].second);
        }
        const double c0 = threadCpuUs();
        const auto t0 = std::chrono::steady_clock::now();
        const StepReport r = model.simulation.step(kDt);
        const auto t1 = std::chrono::steady_clock::now();
        cpu_us.push_back(threadCpuUs() - c0);
        step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        pcg_iterations += r.pcg_iterations;
        substeps += r.substeps;
        newton += r.newton_iterations;
        benchmark::DoNotOptimize(r.energy_j);
    }
    const auto steps = static_cast<double>(step_us.size());
    state.counters["nodes"] = model.simulation.nodeCount();
    state.counters["tets"] = model.simulation.tetCount();
    addPercentiles(state, step_us, "");
    addPercentiles(state, cpu_us, "cpu_");
    state.counters["pcg_iters"] = pcg_iterations / steps;
    state.counters["substeps"] = substeps / steps;
    state.counters["newton_extra"] = newton / steps;
}

// handsim's physics for the shipped default scene (config/scenes/default.yaml: index finger,
// table and block, scripted press_slide_edge) at the scene's rate, with both device outputs
// filled each step: args = resolution, PCG cap, backtracks, substep depth. 1200 steps cover two
// script periods at 100 Hz.
void runDefaultScene(benchmark::State& state, int resolution,
                     const SceneSimulationSettings& settings) {
    config::SceneConfig scene =
        config::loadSceneConfig(HAPTIC_SOURCE_DIR "/config/scenes/default.yaml");
    scene.hand.resolution = resolution;
    DeviceRequest exo{"exo", config::Finger::kIndex, true, {}, 64};
    DeviceRequest thimble{"thimble", config::Finger::kIndex, false, {{0.0, 0.0, -0.012}, {}}, 64};
    SceneSimulation sim(scene, {exo, thimble}, settings);
    const TrackedHand& hand = sim.trackedHand();
    const PressSlideEdgeScript script(hand, scene.hand, *scene.findObject("block"), true);
    sim.reset(script.at(0.0));
    const double dt = 1.0 / scene.rate_hz;
    std::vector<double> step_us;
    double pcg_iterations = 0.0;
    int step = 0;
    msgs::ConstraintSet constraints;
    msgs::ContactSurface surface;
    double substeps = 0.0;
    double backtracks = 0.0;
    double zeroed = 0.0;
    double rescaled = 0.0;
    double restarted = 0.0;
    double newton = 0.0;
    double substepped_us = 0.0;
    int substepped = 0;
    int contacts = 0;
    double process_cpu_us = 0.0;
    for (auto _ : state) {
        const double p0 = processCpuUs();
        const auto t0 = std::chrono::steady_clock::now();
        (void)sim.setHandPose(script.at(++step * dt));
        const StepReport r = sim.step(dt);
        sim.fill(0, constraints);
        sim.fill(1, surface);
        const auto t1 = std::chrono::steady_clock::now();
        process_cpu_us += processCpuUs() - p0;
        step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        pcg_iterations += r.pcg_iterations;
        substeps += r.substeps;
        backtracks += r.backtracks;
        zeroed += r.zeroed_steps;
        rescaled += r.rescaled_steps;
        restarted += r.restarted_solves;
        newton += r.newton_iterations;
        if (r.substeps > 1) {
            substepped_us += step_us.back();
            ++substepped;
        }
        contacts = std::max(contacts, r.active_contacts);
        benchmark::DoNotOptimize(surface.samples.count);
    }
    state.counters["nodes"] = sim.model().simulation.nodeCount();
    state.counters["tets"] = sim.model().simulation.tetCount();
    state.counters["substeps"] = substeps / static_cast<double>(step_us.size());
    state.counters["max_contacts"] = contacts;
    state.counters["backtracks"] = backtracks / static_cast<double>(step_us.size());
    state.counters["zeroed"] = zeroed / static_cast<double>(step_us.size());
    state.counters["rescaled"] = rescaled / static_cast<double>(step_us.size());
    state.counters["restarted"] = restarted / static_cast<double>(step_us.size());
    state.counters["substepped_mean_us"] = substepped > 0 ? substepped_us / substepped : 0.0;
    state.counters["p50_us"] = common::percentile(step_us, 0.5);
    state.counters["p99_us"] = common::percentile(step_us, 0.99);
    state.counters["pcg_iters"] = pcg_iterations / static_cast<double>(step_us.size());
    state.counters["newton_extra"] = newton / static_cast<double>(step_us.size());
    state.counters["process_cpu_mean_us"] = process_cpu_us / static_cast<double>(step_us.size());
}

// The grid: <resolution>/<PCG cap>/<backtracks>/<substep depth>, 5 Newton iterations.
void defaultScene(benchmark::State& state) {
    SceneSimulationSettings settings;
    settings.solver.pcg_max_iterations = static_cast<int>(state.range(1));
    settings.solver.max_backtracks = static_cast<int>(state.range(2));
    settings.solver.max_substep_depth = static_cast<int>(state.range(3));
    runDefaultScene(state, static_cast<int>(state.range(0)), settings);
}

// What handsim runs: realtimeSceneSettings() at <resolution>/<Newton iterations>/<helper
// thread: 1 on, 0 off>. The shipped default scene (solver: block in default.yaml) is 1/2/0:
// solver.helper_thread is off there and on only in thimble_only.yaml. 1/1 is handsim's
// default budget.
void defaultSceneHandsimLimits(benchmark::State& state) {
    config::SolverLimits limits;
    limits.newton_iterations = static_cast<int>(state.range(1));
    SceneSimulationSettings settings = realtimeSceneSettings(limits);
    settings.solver.use_helper_thread = state.range(2) != 0;
    runDefaultScene(state, static_cast<int>(state.range(0)), settings);
}

BENCHMARK(fingertipPress)
    ->ArgsProduct({{0, 1, 2, 3}, {10, 30, 100}})
    ->Unit(benchmark::kMicrosecond)
    ->Iterations(400);
BENCHMARK(fingerFlex)
    ->ArgsProduct({{0, 1, 2}, {10, 30, 100}})
    ->Unit(benchmark::kMicrosecond)
    ->Iterations(400);
BENCHMARK(fingertipPressHandsimLimits)
    ->ArgsProduct({{0, 1, 2}, {30}, {0, 1}})
    ->Unit(benchmark::kMicrosecond)
    ->Iterations(400);
BENCHMARK(fingerFlexHandsimLimits)
    ->ArgsProduct({{0, 1}, {30}, {0, 1}})
    ->Unit(benchmark::kMicrosecond)
    ->Iterations(400);
BENCHMARK(defaultScene)
    ->ArgsProduct({{1, 2}, {10, 30}, {0, 2, 10}, {0, 1, 3}})
    ->Unit(benchmark::kMicrosecond)
    ->Iterations(1200);
BENCHMARK(defaultSceneHandsimLimits)
    ->ArgsProduct({{1, 2}, {1, 2, 5}, {0, 1}})
    ->Unit(benchmark::kMicrosecond)
    ->Iterations(1200);
BENCHMARK(wholeHand)
    ->ArgsProduct({{0, 1, 2}, {10, 30}})
    ->Unit(benchmark::kMicrosecond)
    ->Iterations(200);

}  // namespace
}  // namespace haptic::softhand

// The same heap settings as handsim's main (see there): without them the page faults of the
// per-step matrices double the step time.
int main(int argc, char** argv) {
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
    mallopt(M_TOP_PAD, 64 << 20);
    return haptic::bench::runGoogleBenchmarks(argc, argv);
}
