// Step time of the soft hand, per resolution level and PCG iteration cap.
//   ninja -C build/rel softhand_benchmark && build/rel/tests/softhand/softhand_benchmark
// Scenes: a fingertip pressing 4 mm into a table and sliding (the thimble scene), and one
// finger flexing against a table (the exoskeleton scene), both at 200 Hz (dt = 5 ms).
// Counters: p50_us / p99_us over the steps of the run, pcg_iters per step.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "haptic/softhand/elastic_tracking.hpp"
#include "haptic/softhand/hand_builder.hpp"

namespace haptic::softhand {
namespace {

constexpr double kDt = 0.005;

config::HandConfig handConfig(config::HandModel model, int resolution) {
    config::HandConfig hand;
    hand.model = model;
    hand.finger = config::Finger::kIndex;
    hand.resolution = resolution;
    hand.anthropometry = {0.19, 0.085, 0.016};
    return hand;
}

void report(benchmark::State& state, std::vector<double>& step_us, double pcg_iterations) {
    std::sort(step_us.begin(), step_us.end());
    const auto at = [&](double q) {
        return step_us[static_cast<std::size_t>(q * static_cast<double>(step_us.size() - 1))];
    };
    state.counters["p50_us"] = at(0.5);
    state.counters["p99_us"] = at(0.99);
    state.counters["pcg_iters"] = pcg_iterations / static_cast<double>(step_us.size());
}

void fingertipPress(benchmark::State& state) {
    SolverSettings settings;
    settings.pcg_max_iterations = static_cast<int>(state.range(1));
    settings.contact_stiffness_n_per_m = 3000.0;
    HandModel model = buildHand(
        handConfig(config::HandModel::kFingertip, static_cast<int>(state.range(0))), settings);
    model.simulation.addCollider({HalfSpace{}, Vec3(0.0, 0.0, -0.009), Mat3::Identity(), 0.6});
    const int bone = model.bones.front().body;
    const Vec3 start = model.simulation.bodyPosition(bone);
    std::vector<double> step_us;
    double pcg_iterations = 0.0;
    double backtracks = 0.0;
    double substeps = 0.0;
    int step = 0;
    for (auto _ : state) {
        const double t = (step++ % 200) * kDt;  // 1 s cycle: press 4 mm, slide 1 cm, lift
        const double press = t < 0.2 ? t / 0.2 : (t < 0.8 ? 1.0 : (1.0 - t) / 0.2);
        const double slide = t < 0.2 ? 0.0 : std::min(1.0, (t - 0.2) / 0.6);
        model.simulation.setTrackingTarget(bone, start + Vec3(0.01 * slide, 0.0, -0.005 * press),
                                           Mat3::Identity());
        const auto t0 = std::chrono::steady_clock::now();
        const StepReport r = model.simulation.step(kDt);
        const auto t1 = std::chrono::steady_clock::now();
        step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        pcg_iterations += r.pcg_iterations;
        backtracks += r.backtracks;
        substeps += r.substeps;
        benchmark::DoNotOptimize(r.energy_j);
    }
    state.counters["nodes"] = model.simulation.nodeCount();
    state.counters["tets"] = model.simulation.tetCount();
    report(state, step_us, pcg_iterations);
    state.counters["backtracks"] = backtracks / static_cast<double>(step_us.size());
    state.counters["substeps"] = substeps / static_cast<double>(step_us.size());
}

void fingerFlex(benchmark::State& state) {
    SolverSettings settings;
    settings.pcg_max_iterations = static_cast<int>(state.range(1));
    settings.contact_stiffness_n_per_m = 3000.0;
    HandModel model = buildHand(
        handConfig(config::HandModel::kFinger, static_cast<int>(state.range(0))), settings);
    model.simulation.addCollider({HalfSpace{}, Vec3(0.0, 0.0, -0.03), Mat3::Identity(), 0.6});
    ElasticTracking tracking(model);
    std::vector<BonePose> build;
    for (const auto& bone : model.bones) {
        build.push_back(
            {model.simulation.bodyPosition(bone.body), model.simulation.bodyRotation(bone.body)});
    }
    std::vector<double> step_us;
    double pcg_iterations = 0.0;
    double backtracks = 0.0;
    double substeps = 0.0;
    int step = 0;
    for (auto _ : state) {
        // Flex all three joints together by up to 0.8 rad and back, 1 s period; the palm
        // is lowered so the fingertip meets the table at the end of the flexion.
        const double t = (step++ % 200) * kDt;
        const double angle = 0.8 * std::sin(3.14159265 * t);
        std::vector<BonePose> poses = build;
        Vec3 joint = build[0].position_m + Vec3(0.5 * 0.45 * 0.19, 0.0, 0.0);
        Mat3 rotation = Mat3::Identity();
        for (std::size_t k = 1; k < poses.size(); ++k) {
            rotation = rotation * Eigen::AngleAxisd(angle / 3.0, Vec3::UnitY()).toRotationMatrix();
            const double length = model.bones[k].length_m;
            poses[k] = {joint + rotation * Vec3(0.5 * length, 0.0, 0.0), rotation};
            joint += rotation * Vec3(length, 0.0, 0.0);
        }
        tracking.setTrackedPoses(poses, nullptr);
        const auto t0 = std::chrono::steady_clock::now();
        tracking.update(model, kDt);
        const StepReport r = model.simulation.step(kDt);
        const auto t1 = std::chrono::steady_clock::now();
        step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        pcg_iterations += r.pcg_iterations;
        backtracks += r.backtracks;
        substeps += r.substeps;
        benchmark::DoNotOptimize(r.energy_j);
    }
    state.counters["nodes"] = model.simulation.nodeCount();
    state.counters["tets"] = model.simulation.tetCount();
    report(state, step_us, pcg_iterations);
    state.counters["backtracks"] = backtracks / static_cast<double>(step_us.size());
    state.counters["substeps"] = substeps / static_cast<double>(step_us.size());
}

BENCHMARK(fingertipPress)
    ->ArgsProduct({{1, 2, 3, 4}, {10, 30, 100}})
    ->Unit(benchmark::kMicrosecond)
    ->Iterations(400);
BENCHMARK(fingerFlex)
    ->ArgsProduct({{1, 2, 3}, {10, 30, 100}})
    ->Unit(benchmark::kMicrosecond)
    ->Iterations(400);

}  // namespace
}  // namespace haptic::softhand

BENCHMARK_MAIN();
