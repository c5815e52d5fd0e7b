#pragma once

// The fingertip press + slide scene of the soft-hand benchmark (thimble scene: distal phalanx
// and its pad; the bone's tracking target presses 5 mm towards a table 1 mm below the pad,
// slides 1 cm and lifts, once per second at dt = 5 ms), shared by softhand_benchmark and the
// Bullet deformable-body comparison so both run, and are scored against, the same scene.

#include <array>
#include <vector>

#include "haptic/softhand/hand_builder.hpp"
#include "haptic/softhand/simulation.hpp"

namespace haptic::softhand::bench {

constexpr double kDt = 0.005;
constexpr int kCycleSteps = 200;  // one scripted cycle: 1 s
constexpr int kPressSteps = 40;   // the first 0.2 s: pressing in, before any sliding
constexpr int kPressReferenceLevel = 4;
constexpr double kTableHeightM = -0.009;
constexpr double kTableFriction = 0.6;
constexpr double kContactStiffnessNPerM = 3000.0;

[[nodiscard]] config::HandConfig handConfig(config::HandModel model, int resolution);
[[nodiscard]] SolverSettings solverSettings(int pcg_cap, double pcg_tolerance);

// Offset of the bone's tracking target from its build pose at `step` (press, slide, lift).
[[nodiscard]] Vec3 pressTargetOffset(int step);

struct Sample {
    double table_force_n;  // z of the force the tissue exerts on the table (negative = down)
    Vec3 tip_m;            // distal bone centre
};

class FingertipPress {
  public:
    FingertipPress(int level, int pcg_cap, double pcg_tolerance);
    void setInput(int step);
    StepReport step() { return stepBy(kDt); }
    StepReport stepBy(double dt_s) { return model_.simulation.step(dt_s); }
    [[nodiscard]] Sample sample() const;
    [[nodiscard]] const Simulation& simulation() const { return model_.simulation; }
    [[nodiscard]] SolverSettings& solver() { return model_.simulation.settings(); }
    [[nodiscard]] const HandModel& model() const { return model_; }
    [[nodiscard]] int table() const { return table_; }
    [[nodiscard]] int distalBody() const { return bone_; }

  private:
    HandModel model_;
    int table_{0};
    int bone_{0};
    Vec3 start_;
};

// The fingertip as the hand builder makes it, for another solver: the tissue mesh (same nodes
// in the same order as the Simulation's, same tetrahedra), the distal bone as a rigid body
// and the nodes the builder couples to it.
struct FingertipModel {
    TetMesh mesh;
    TissueMaterial material;
    double bone_mass_kg{0.0};
    Vec3 bone_inertia_kg_m2{Vec3::Zero()};  // principal, bone frame (x along the bone)
    Vec3 bone_position_m{Vec3::Zero()};
    std::vector<int> bone_nodes;
    double tracking_linear_n_per_m{0.0};
    double tracking_angular_nm_per_rad{0.0};
};
[[nodiscard]] FingertipModel fingertipModel(int level);

// The converged reference trace (level kPressReferenceLevel, PCG to 1e-8 with up to 2000
// iterations), one sample per step of the first cycle. Read from `cache_path` if that file
// exists, else computed (minutes) and written there; an empty path always computes.
[[nodiscard]] std::vector<Sample> pressReference(const char* cache_path);

// Errors of a trace against the reference, as in softhand_benchmark.
struct TraceError {
    double press_err;   // RMS(F - F_ref) / RMS(F_ref) over the first kPressSteps
    double force_err;   // the same over the whole cycle
    double tip_err_mm;  // RMS distance of the bone centre over the whole cycle
};
[[nodiscard]] TraceError traceError(const std::vector<Sample>& trace,
                                    const std::vector<Sample>& reference);

}  // namespace haptic::softhand::bench
