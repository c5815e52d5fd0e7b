// The soft hand's speed/accuracy trade (#20): every combination of mesh resolution level,
// Newton iterations, PCG cap and time step, each run under handsim's real-time limits
// (withRealtimeLimits: 2 halvings, no substeps, the given Newton count and cap), against a
// converged reference of the same scene. One CSV row per combination on stdout;
// scripts/softhand-tradeoff.sh turns it into the table and the Pareto PNG of
// docs/benchmarks.md.
//   ninja -C build/release softhand_tradeoff && build/release/tests/bench/softhand_tradeoff
//
// A PCG cap of 0 stands for the sparse direct solver (SimplicialLDLT, LinearSolver::kSparseLdlt),
// so the two solvers stand side by side on the same fronts.
//
// Scenes (tests/softhand): "press", the thimble scene (the distal phalanx presses 5 mm towards
// a table, slides 1 cm and lifts); "flex", the exoskeleton's scene (one finger flexes against a
// table). Two 1 s cycles a row; times over both, errors over the first:
//   press_err  RMS(F - F_ref) / RMS(F_ref) of the table's normal force over the first 0.2 s
//              (pressing in, before the reference's stick-slip while sliding)
//   force_err  the same over the cycle
//   area_err   RMS(A - A_ref) / RMS(A_ref) of the contact area: the convex hull of the tissue
//              nodes touching the table, projected on it
//   tip_err_mm RMS distance of the distal bone's centre
//   angle_err_deg RMS difference of the distal bone's pitch (its flexion for "flex")
// Errors are taken at each step of the row, against the reference at the same time. The
// reference is the same scene one level finer than the finest row (press: level 4, flex:
// level 3), stepped at 5 ms with the solver's own defaults (5 Newton iterations, 10 halvings,
// substeps) and PCG to 1e-8 (up to 2000 iterations). It is this project's solver, converged; an
// independent reference is #21's work. Its time step is 5 ms, so rows at 5 ms carry no time
// discretisation error against it and rows at 10 ms carry theirs.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "finger_flex_scene.hpp"
#include "fingertip_press_scene.hpp"
#include "haptic/common/statistics.hpp"
#include "haptic/config/scene.hpp"
#include "haptic/softhand/scene_simulation.hpp"
#include "provenance.hpp"
#include "thread_cpu_time.hpp"

namespace haptic::softhand::bench {
namespace {
using haptic::bench::threadCpuUs;

constexpr int kPressReference = kPressReferenceLevel;
constexpr int kFlexReference = 3;

struct Observation {
    double table_force_n{0.0};
    double contact_area_m2{0.0};
    Vec3 tip_m{Vec3::Zero()};
    double pitch_rad{0.0};
};

// Area of the convex hull of points in a plane (Andrew's monotone chain).
double hullArea(std::vector<Eigen::Vector2d> points) {
    if (points.size() < 3) {
        return 0.0;
    }
    std::sort(points.begin(), points.end(), [](const auto& a, const auto& b) {
        return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
    const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a,
                          const Eigen::Vector2d& b) {
        return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
    };
    std::vector<Eigen::Vector2d> hull(2 * points.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) {
            --k;
        }
        hull[k++] = points[i];
    }
    for (std::size_t i = points.size() - 1, lower = k + 1; i > 0; --i) {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i - 1]) <= 0.0) {
            --k;
        }
        hull[k++] = points[i - 1];
    }
    double twice_area = 0.0;
    for (std::size_t i = 0; i + 1 < k; ++i) {
        twice_area += hull[i].x() * hull[i + 1].y() - hull[i + 1].x() * hull[i].y();
    }
    return 0.5 * std::fabs(twice_area);
}

template <typename Scene>
Observation observe(const Scene& scene) {
    const Simulation& sim = scene.simulation();
    Observation out;
    out.table_force_n = sim.forceOnCollider(scene.table()).z();
    std::vector<Eigen::Vector2d> touching;
    for (const auto& contact : sim.contactForces()) {
        if (contact.collider == scene.table() && contact.force_n.squaredNorm() > 0.0) {
            touching.push_back(sim.nodePosition(contact.node).template head<2>());
        }
    }
    out.contact_area_m2 = hullArea(std::move(touching));
    out.tip_m = sim.bodyPosition(scene.distalBody());
    const Mat3& rotation = sim.bodyRotation(scene.distalBody());
    out.pitch_rad = std::atan2(-rotation(2, 0), rotation(0, 0));
    return out;
}

template <typename Scene>
std::vector<Observation> referenceTrace(int level) {
    Scene scene(level, 2000, 1e-8);
    std::vector<Observation> trace;
    for (int s = 0; s < kCycleSteps; ++s) {
        scene.setInput(s);
        scene.step();
        trace.push_back(observe(scene));
    }
    return trace;
}

struct Row {
    const char* scene;
    int level;
    int newton;
    int pcg_cap;  // 0: the sparse direct solver (SimplicialLDLT) instead of PCG
    int dt_ms;
};

// Sums of squares for a relative or absolute RMS.
struct Rms {
    double error2{0.0};
    double reference2{0.0};
    int count{0};
    void add(double value, double reference) {
        error2 += (value - reference) * (value - reference);
        reference2 += reference * reference;
        ++count;
    }
    void addSquaredDistance(double distance2) {
        error2 += distance2;
        ++count;
    }
    [[nodiscard]] double relative() const {
        return std::sqrt(error2 / std::max(reference2, 1e-30));
    }
    [[nodiscard]] double absolute() const { return std::sqrt(error2 / std::max(count, 1)); }
};

template <typename Scene>
void runRow(const Row& row, const std::vector<Observation>& reference) {
    Scene scene(row.level, row.pcg_cap, 1e-4);
    config::SolverLimits limits;
    limits.newton_iterations = row.newton;
    limits.pcg_max_iterations = row.pcg_cap;
    scene.solver() = withRealtimeLimits(scene.solver(), limits);
    if (row.pcg_cap == 0) {
        scene.solver().linear_solver = LinearSolver::kSparseLdlt;
        scene.solver().pcg_max_iterations = 30;  // its fallback, should a factorisation fail
    }
    const int stride = row.dt_ms / 5;  // reference steps (kDt = 5 ms) per step of this row
    const double dt_s = 1e-3 * row.dt_ms;
    const int cycle_steps = kCycleSteps / stride;
    std::vector<double> wall_us;
    std::vector<double> cpu_us;
    Rms press;
    Rms force;
    Rms area;
    Rms tip;
    Rms angle;
    int rescaled = 0;
    int zeroed = 0;
    for (int step = 0; step < 2 * cycle_steps; ++step) {
        scene.setInput(step * stride);
        const double c0 = threadCpuUs();
        const auto t0 = std::chrono::steady_clock::now();
        const StepReport report = scene.stepBy(dt_s);
        const auto t1 = std::chrono::steady_clock::now();
        cpu_us.push_back(threadCpuUs() - c0);
        wall_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        rescaled += report.rescaled_steps;
        zeroed += report.zeroed_steps;
        if (step >= cycle_steps) {
            continue;
        }
        // The state after this step is the reference's after its step (step + 1) * stride - 1.
        const Observation now = observe(scene);
        const Observation& expected = reference[static_cast<std::size_t>((step + 1) * stride - 1)];
        force.add(now.table_force_n, expected.table_force_n);
        if ((step + 1) * stride <= kPressSteps) {
            press.add(now.table_force_n, expected.table_force_n);
        }
        area.add(now.contact_area_m2, expected.contact_area_m2);
        tip.addSquaredDistance((now.tip_m - expected.tip_m).squaredNorm());
        angle.add(now.pitch_rad, expected.pitch_rad);
    }
    const auto steps = static_cast<double>(wall_us.size());
    std::printf("%s,%d,%d,%d,%d,%d,%.1f,%.1f,%.1f,%.1f,%.4f,%.4f,%.4f,%.4f,%.3f,%.4f,%.4f,%s\n",
                row.scene, row.level, scene.simulation().nodeCount(), row.newton, row.pcg_cap,
                row.dt_ms, common::percentile(wall_us, 0.5), common::percentile(wall_us, 0.99),
                common::percentile(cpu_us, 0.5), common::percentile(cpu_us, 0.99), press.relative(),
                force.relative(), area.relative(), 1e3 * tip.absolute(),
                angle.absolute() * 180.0 / 3.14159265358979, rescaled / steps, zeroed / steps,
                row.pcg_cap == 0 ? "ldlt" : "pcg");
    std::fflush(stdout);
}

}  // namespace
}  // namespace haptic::softhand::bench

int main(int argc, char** argv) {
    using namespace haptic::softhand::bench;
    CLI::App app{"softhand_tradeoff - the soft hand's step time against its error, per setting"};
    std::vector<std::string> scenes{"press", "flex"};
    std::vector<int> level_list{0, 1, 2};
    std::vector<int> newton_list{1, 2, 3};
    std::vector<int> cap_list{0, 10, 30, 100};
    std::vector<int> dt_list{5, 10};
    app.add_option("--scenes", scenes, "press, flex or both")
        ->delimiter(',')
        ->check(CLI::IsMember({"press", "flex"}))
        ->capture_default_str();
    app.add_option("--levels", level_list, "resolution levels (below the reference's)")
        ->delimiter(',')
        ->capture_default_str();
    app.add_option("--newton", newton_list, "Newton iterations per step")
        ->delimiter(',')
        ->capture_default_str();
    app.add_option("--pcg-caps", cap_list,
                   "PCG iteration caps; 0 solves each Newton system with SimplicialLDLT instead")
        ->delimiter(',')
        ->capture_default_str();
    app.add_option("--dt-ms", dt_list, "time steps, multiples of 5 ms")
        ->delimiter(',')
        ->capture_default_str();
    CLI11_PARSE(app, argc, argv);
    haptic::bench::printProvenance(argc, argv);

    for (const int dt : dt_list) {
        if (dt <= 0 || dt % 5 != 0 || kCycleSteps % (dt / 5) != 0) {
            std::fprintf(stderr, "softhand_tradeoff: --dt-ms %d is not a divisor of 1 s in 5 ms\n",
                         dt);
            return 2;
        }
    }
    std::printf(
        "scene,level,nodes,newton,pcg_cap,dt_ms,p50_us,p99_us,cpu_p50_us,cpu_p99_us,press_err,"
        "force_err,area_err,tip_err_mm,angle_err_deg,rescaled,zeroed,solver\n");
    const auto sweep = [&](const char* name, auto run, const auto& reference) {
        for (const int level : level_list) {
            for (const int newton : newton_list) {
                for (const int cap : cap_list) {
                    for (const int dt : dt_list) {
                        run(Row{name, level, newton, cap, dt}, reference);
                    }
                }
            }
        }
    };
    const auto wanted = [&](const std::string& scene) {
        return std::find(scenes.begin(), scenes.end(), scene) != scenes.end();
    };
    if (wanted("press")) {
        sweep("press", runRow<FingertipPress>, referenceTrace<FingertipPress>(kPressReference));
    }
    if (wanted("flex")) {
        sweep("flex", runRow<FingerFlex>, referenceTrace<FingerFlex>(kFlexReference));
    }
    return 0;
}
