// Google Benchmark of one contact-optimiser solve with 64 pad samples (target: p99 < 50 us),
// and of the pad safety limiter that follows it every tick (BM_PadLimit...: with the shipped
// limits, and with a 0.05 N force limit that makes it bisect on every tick).
// Each solve is timed on its own, so the p50/p99/max counters are per-solve wall-clock
// latencies (they include preemption by other processes on a loaded machine); cpu_p50/p99 are
// the same percentiles of the thread's CPU time. `allocations` counts operator new calls
// inside the timed solves (must be 0).
//
//   build/release/tests/bench/tactile_benchmark --benchmark_repetitions=1

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <vector>

#include "allocation_counter.hpp"
#include "haptic/common/statistics.hpp"
#include "haptic/config/device.hpp"
#include "haptic/tactile/contact_optimiser.hpp"
#include "haptic/tactile/fingertip_model.hpp"
#include "haptic/tactile/pad_safety.hpp"

namespace {

using haptic::tactile::ContactSurfaceOptimiser;
using haptic::tactile::NonlinearPadModel;

constexpr int kSamples = 64;

struct Fixture {
    haptic::config::ThimbleConfig config{
        haptic::config::loadDeviceConfig(HAPTIC_DEFAULT_THIMBLE_CONFIG).thimble()};
    haptic::tactile::ThimbleKinematics kinematics{config};
    NonlinearPadModel pad{haptic::tactile::PadModelParameters{}};

    // A 10 mm sphere rolling across the pad and pressing in and out: consecutive frames of a
    // simulation running slower than the 1 kHz loop.
    std::vector<haptic::msgs::ContactSurface> movingSphere(int frames) const {
        std::vector<haptic::msgs::ContactSurface> out;
        for (int k = 0; k < frames; ++k) {
            const double phase = 2.0 * 3.14159265358979 * k / frames;
            const double depth = 0.001 + 0.0008 * std::sin(3.0 * phase);
            const Eigen::Vector3d centre(0.003 * std::cos(phase), 0.003 * std::sin(phase),
                                         0.018 - depth + 0.010);
            out.push_back(pad.contactSurface(haptic::tactile::SphereObstacle(centre, 0.010),
                                             kSamples,
                                             haptic::tactile::SampleWeighting::kContactStiffness));
        }
        return out;
    }

    haptic::msgs::ContactSurface steepPlane() const {
        const Eigen::Vector3d n(-std::sin(0.8), 0.0, -std::cos(0.8));
        const Eigen::Vector3d centre(0.0, 0.0, 0.009);
        return pad.contactSurface(haptic::tactile::HalfSpaceObstacle(centre - 0.0075 * n, n),
                                  kSamples, haptic::tactile::SampleWeighting::kContactStiffness);
    }
};

double threadCpuSeconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Times calls one by one: wall-clock and thread-CPU time and the allocations inside each
// timed call, reported as the counters every benchmark here prints.
class CallTimer {
  public:
    CallTimer() {
        wall_us_.reserve(1 << 20);
        cpu_us_.reserve(1 << 20);
    }

    template <typename Call>
    auto time(benchmark::State& state, Call&& call) {
        haptic::testing::ScopedAllocationCounter counter;
        const double cpu_start = threadCpuSeconds();
        const auto start = std::chrono::steady_clock::now();
        auto result = call();
        const auto stop = std::chrono::steady_clock::now();
        const double cpu_stop = threadCpuSeconds();
        allocations_ += counter.allocations();
        benchmark::DoNotOptimize(result);
        const double seconds = std::chrono::duration<double>(stop - start).count();
        state.SetIterationTime(seconds);
        if (wall_us_.size() < wall_us_.capacity()) {
            wall_us_.push_back(seconds * 1e6);
            cpu_us_.push_back((cpu_stop - cpu_start) * 1e6);
        }
        return result;
    }

    void report(benchmark::State& state) {
        const haptic::common::PercentileSummary wall = haptic::common::summarize(wall_us_);
        const haptic::common::PercentileSummary cpu = haptic::common::summarize(cpu_us_);
        state.counters["p50_us"] = wall.p50;
        state.counters["p99_us"] = wall.p99;
        state.counters["max_us"] = wall.max;
        state.counters["cpu_p50_us"] = cpu.p50;
        state.counters["cpu_p99_us"] = cpu.p99;
        state.counters["allocations"] = static_cast<double>(allocations_);
    }

  private:
    std::vector<double> wall_us_;
    std::vector<double> cpu_us_;
    std::uint64_t allocations_{0};
};

template <typename NextSurface>
void runSolves(benchmark::State& state, ContactSurfaceOptimiser& optimiser, bool cold,
               NextSurface next) {
    CallTimer timer;
    long iterations_sum = 0;
    int iterations_max = 0;
    long solves = 0;
    for (auto _ : state) {
        const haptic::msgs::ContactSurface& surface = next();
        if (cold) {
            optimiser.reset();
        }
        const auto command = timer.time(state, [&] { return optimiser.solve(surface); });
        iterations_sum += command.report.iterations;
        iterations_max = std::max(iterations_max, command.report.iterations);
        ++solves;
    }
    timer.report(state);
    state.counters["iterations_mean"] =
        static_cast<double>(iterations_sum) / static_cast<double>(std::max(solves, 1L));
    state.counters["iterations_max"] = iterations_max;
}

void BM_SolveWarmMovingSphere(benchmark::State& state) {
    const Fixture f;
    const auto frames = f.movingSphere(240);
    ContactSurfaceOptimiser optimiser(f.kinematics,
                                      haptic::tactile::OptimiserSettings::fromConfig(f.config));
    std::size_t k = 0;
    runSolves(
        state, optimiser, false, [&]() -> const auto& { return frames[k++ % frames.size()]; });
}

void BM_SolveColdFromRetract(benchmark::State& state) {
    const Fixture f;
    const auto frames = f.movingSphere(240);
    ContactSurfaceOptimiser optimiser(f.kinematics,
                                      haptic::tactile::OptimiserSettings::fromConfig(f.config));
    std::size_t k = 0;
    runSolves(
        state, optimiser, true, [&]() -> const auto& { return frames[k++ % frames.size()]; });
}

void BM_SolveClampedSteepPlane(benchmark::State& state) {
    const Fixture f;
    const auto plane = f.steepPlane();
    ContactSurfaceOptimiser optimiser(f.kinematics,
                                      haptic::tactile::OptimiserSettings::fromConfig(f.config));
    runSolves(
        state, optimiser, true, [&]() -> const auto& { return plane; });
}

// The limiter as ThimbleChannel calls it each tick: the blend from the retract pose to the
// solved pose of the newest frame (a 100 Hz sim: a new frame every 10 ticks), at full gain,
// then the pose sent as the next reference (servos that follow exactly: no forward
// kinematics and no shortened servo step, which the channel adds when a servo lags).
void BM_PadLimitMovingSphere(benchmark::State& state) {
    const Fixture f;
    const auto frames = f.movingSphere(240);
    ContactSurfaceOptimiser optimiser(f.kinematics,
                                      haptic::tactile::OptimiserSettings::fromConfig(f.config));
    std::vector<haptic::tactile::PlatformDofs> solved;
    for (const auto& frame : frames) {
        solved.push_back(optimiser.solve(frame).dofs);
    }
    haptic::config::DeviceConfig device =
        haptic::config::loadDeviceConfig(HAPTIC_DEFAULT_THIMBLE_CONFIG);
    if (state.range(0) == 1) {
        device.safety.max_force_n = 0.05;
    }
    haptic::tactile::PadSafetyLimiter limiter(
        haptic::tactile::PadSafetySettings::fromConfig(device, 1e-3));
    const haptic::tactile::PlatformDofs retract = f.kinematics.retractPose();
    CallTimer timer;
    long ticks = 0;
    long limited = 0;
    for (auto _ : state) {
        const std::size_t frame = static_cast<std::size_t>(ticks / 10) % frames.size();
        const haptic::tactile::PlatformDofs& target = solved[frame];
        const auto pose_at = [&](double gain, haptic::tactile::PlatformPose& pose) {
            haptic::tactile::PlatformDofs dofs;
            dofs.height_m = retract.height_m + gain * (target.height_m - retract.height_m);
            dofs.tilt_x_rad = retract.tilt_x_rad + gain * (target.tilt_x_rad - retract.tilt_x_rad);
            dofs.tilt_y_rad = retract.tilt_y_rad + gain * (target.tilt_y_rad - retract.tilt_y_rad);
            return f.kinematics.platformPose(dofs, pose) == haptic::tactile::KinematicsError::kNone;
        };
        const haptic::tactile::PadLimit limit = timer.time(state, [&] {
            const haptic::tactile::PadLimit result = limiter.limit(1.0, &frames[frame], pose_at);
            (void)limiter.commanded(result.pose, &frames[frame]);
            return result;
        });
        limited += limit.flags != 0 ? 1 : 0;
        ++ticks;
    }
    timer.report(state);
    state.counters["limited_share"] =
        static_cast<double>(limited) / static_cast<double>(std::max(ticks, 1L));
}

BENCHMARK(BM_SolveWarmMovingSphere)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SolveColdFromRetract)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SolveClampedSteepPlane)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PadLimitMovingSphere)
    ->ArgName("tight")
    ->Arg(0)
    ->Arg(1)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);

}  // namespace
