// The fingertip press of softhand_benchmark run through Bullet's own deformable-body solver
// (BulletSoftBody, btDeformableMultiBodyDynamicsWorld) next to the soft hand's solver: same
// tetrahedral mesh per resolution level, material, masses, dt = 5 ms, scripted bone target,
// table friction; both scored against the same converged reference (the soft hand at level 4,
// PCG to 1e-8). Results and their discussion: docs/benchmarks.md.
//
//   ninja -C build/release bullet_deformable_benchmark
//   build/release/tests/bench/bullet_deformable_benchmark --reference=press_reference_l4.txt
//
// Options: --reference=FILE caches the reference trace (computed, minutes, if FILE is
// missing); --levels=123; --steps=400; --ours=0 skips the soft hand rows; --traces=DIR writes
// each row's per-step force and bone position.

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bullet_fingertip.hpp"
#include "fingertip_press_scene.hpp"
#include "haptic/common/statistics.hpp"
#include "provenance.hpp"
#include "thread_cpu_time.hpp"

namespace haptic::softhand::bench {
namespace {
using haptic::bench::threadCpuUs;

struct Options {
    std::string reference_cache;
    std::string levels{"123"};
    int steps{400};
    bool ours{true};
    std::string traces;
};

struct Row {
    std::string solver;
    int level{0};
    int cap{0};
    int nodes{0};
    int tets{0};
    double p50_us{0.0};
    double p99_us{0.0};
    double cpu_mean_us{0.0};
    TraceError error{};
    bool finite{true};
    int steps{0};               // run until it diverged, or options.steps
    double distortion_mm{0.0};  // largest node distance from the bone's rigid motion
    int compared{0};            // samples of the first cycle before any divergence
};

// Steps `scene` (setInput(step) then step()), timing the step call; the first cycle's samples
// are kept for the error. `finite` ends the run early if the state blew up.
template <typename SetInput, typename Step, typename Get, typename Finite, typename Distortion>
Row measure(const Options& options, const std::vector<Sample>& reference, SetInput set_input,
            Step step, Get get, Finite finite, Distortion distortion,
            const std::string& trace_name) {
    Row row;
    std::vector<double> step_us;
    std::vector<Sample> trace;
    double cpu_us = 0.0;
    for (int s = 0; s < options.steps; ++s) {
        set_input(s);
        const double c0 = threadCpuUs();
        const auto t0 = std::chrono::steady_clock::now();
        step();
        const auto t1 = std::chrono::steady_clock::now();
        cpu_us += threadCpuUs() - c0;
        step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        if (s < kCycleSteps) {
            trace.push_back(get());
        }
        row.distortion_mm = std::max(row.distortion_mm, 1e3 * distortion());
        if (!finite()) {
            row.finite = false;
            row.steps = s + 1;
            if (!trace.empty() && static_cast<int>(trace.size()) == s + 1) {
                trace.pop_back();  // the diverged sample itself
            }
            break;
        }
    }
    if (!options.traces.empty()) {
        const std::string path = options.traces + "/" + trace_name + ".txt";
        if (std::FILE* out = std::fopen(path.c_str(), "w")) {
            for (std::size_t i = 0; i < trace.size(); ++i) {
                std::fprintf(out, "%zu %.6g %.6g %.6g %.6g %.6g\n", i, trace[i].table_force_n,
                             reference[i].table_force_n, trace[i].tip_m.x(), trace[i].tip_m.z(),
                             reference[i].tip_m.z());
            }
            std::fclose(out);
        }
    }
    std::vector<double> samples = step_us;
    row.p50_us = common::percentile(samples, 0.5);
    row.p99_us = common::percentile(samples, 0.99);
    row.cpu_mean_us = cpu_us / static_cast<double>(step_us.size());
    if (!trace.empty()) {
        row.error = traceError(trace, reference);
    }
    row.compared = static_cast<int>(trace.size());
    return row;
}

Row runOurs(const Options& options, const std::vector<Sample>& reference, int level, int cap) {
    FingertipPress scene(level, cap, 1e-4);
    Row row = measure(
        options, reference, [&](int s) { scene.setInput(s); }, [&] { (void)scene.step(); },
        [&] { return scene.sample(); }, [] { return true; },
        [&] {
            const Simulation& sim = scene.simulation();
            const int bone = scene.model().bones.front().body;
            const Vec3 shift = sim.bodyPosition(bone) - scene.model().bones.front().rest_position_m;
            double worst = 0.0;
            for (int i = 0; i < sim.nodeCount(); ++i) {
                worst =
                    std::max(worst, (sim.nodePosition(i) - sim.nodeRestPosition(i) - shift).norm());
            }
            return worst;
        },
        "softhand_l" + std::to_string(level) + "_cap" + std::to_string(cap));
    row.solver = "soft hand (PCG cap)";
    row.level = level;
    row.cap = cap;
    row.nodes = scene.simulation().nodeCount();
    row.tets = scene.simulation().tetCount();
    return row;
}

Row runBullet(const Options& options, const std::vector<Sample>& reference, int level, int cap,
              BoneDrive drive, bool implicit) {
    const FingertipModel model = fingertipModel(level);
    BulletSettings settings;
    settings.drive = drive;
    settings.krylov_iterations = cap;
    settings.implicit = implicit;
    BulletFingertip scene(model, solverSettings(30, 1e-4), settings);
    const bool tracked = drive == BoneDrive::kTracked;
    Row row = measure(
        options, reference,
        [&](int s) {
            scene.setBoneTarget(tracked
                                    ? model.bone_position_m + pressTargetOffset(s)
                                    : reference[static_cast<std::size_t>(s % kCycleSteps)].tip_m);
        },
        [&] { scene.step(kDt); }, [&] { return scene.sample(); }, [&] { return scene.finite(); },
        [&] { return scene.maxDistortion(); },
        std::string(tracked ? "bullet_tracked" : "bullet_kinematic") +
            (implicit ? "" : "_explicit") + "_l" + std::to_string(level) + "_cap" +
            std::to_string(cap));
    row.solver = std::string("Bullet ") + (implicit ? "implicit" : "explicit elasticity") +
                 (tracked ? ", tracked bone" : ", bone on ref. path") + " (CG cap)";
    row.level = level;
    row.cap = cap;
    row.nodes = scene.nodeCount();
    row.tets = scene.tetCount();
    return row;
}

std::string number(double value, bool valid) {
    if (!valid) {
        return "-";
    }
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", value);
    return text;
}

// Errors only over what ran: press err needs the whole press (kPressSteps), force and tip
// err the whole cycle.
void print(const Row& r) {
    const bool press = r.compared >= kPressSteps;
    const bool cycle = r.compared >= kCycleSteps;
    std::printf("| %s | %d | %d | %d / %d | %.0f | %.0f | %.0f | %s | %s | %s | %.3g | %s |\n",
                r.solver.c_str(), r.level, r.cap, r.nodes, r.tets, r.p50_us, r.p99_us,
                r.cpu_mean_us, number(r.error.press_err, press).c_str(),
                number(r.error.force_err, cycle).c_str(), number(r.error.tip_err_mm, cycle).c_str(),
                r.distortion_mm,
                r.finite ? "ran" : ("diverged at step " + std::to_string(r.steps)).c_str());
    std::fflush(stdout);
}

int run(const Options& options) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<Sample> reference = pressReference(options.reference_cache.c_str());
    std::printf("reference (soft hand level %d, PCG 1e-8 / 2000): %.1f s; peak |F| %.3f N\n",
                kPressReferenceLevel,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                std::abs(std::min_element(reference.begin(), reference.end(),
                                          [](const Sample& a, const Sample& b) {
                                              return a.table_force_n < b.table_force_n;
                                          })
                             ->table_force_n));
    std::printf(
        "| solver | level | cap | nodes / tets | p50 (us) | p99 (us) | mean CPU (us) | press err "
        "| force err | tip err (mm) | max distortion (mm) | state "
        "|\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const char c : options.levels) {
        const int level = c - '0';
        if (options.ours) {
            for (const int cap : {10, 30, 100}) {
                print(runOurs(options, reference, level, cap));
            }
        }
        print(runBullet(options, reference, level, 300, BoneDrive::kTracked, true));
        for (const int cap : {30, 300}) {
            print(runBullet(options, reference, level, cap, BoneDrive::kKinematic, true));
        }
        print(runBullet(options, reference, level, 300, BoneDrive::kKinematic, false));
    }
    return 0;
}

}  // namespace
}  // namespace haptic::softhand::bench

int main(int argc, char** argv) {
    haptic::bench::printProvenance(argc, argv);
    // Same heap settings as softhand_benchmark and handsim (page faults of per-step buffers).
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
    mallopt(M_TOP_PAD, 64 << 20);
    haptic::softhand::bench::Options options;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const auto value = [&](const char* key) -> const char* {
            const std::size_t n = std::strlen(key);
            return arg.compare(0, n, key) == 0 ? arg.c_str() + n : nullptr;
        };
        if (const char* v = value("--reference=")) {
            options.reference_cache = v;
        } else if (const char* v = value("--levels=")) {
            options.levels = v;
        } else if (const char* v = value("--steps=")) {
            options.steps = std::max(haptic::softhand::bench::kCycleSteps, std::atoi(v));
        } else if (const char* v = value("--ours=")) {
            options.ours = std::strcmp(v, "0") != 0;
        } else if (const char* v = value("--traces=")) {
            options.traces = v;
        } else {
            std::fprintf(stderr, "unknown argument %s (see the header of %s)\n", argv[i], __FILE__);
            return 2;
        }
    }
    return haptic::softhand::bench::run(options);
}
