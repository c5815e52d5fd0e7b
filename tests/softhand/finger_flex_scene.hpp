#pragma once

// The finger flex scene of the soft-hand benchmarks (the exoskeleton's scene): one finger
// flexing all three joints by up to 0.8 rad and back within each 1 s cycle, its tip meeting a
// table at the end of the flexion. Shared by softhand_benchmark and softhand_tradeoff.

#include <vector>

#include "fingertip_press_scene.hpp"
#include "haptic/softhand/elastic_tracking.hpp"
#include "haptic/softhand/hand_builder.hpp"

namespace haptic::softhand::bench {

class FingerFlex {
  public:
    FingerFlex(int level, int pcg_cap, double pcg_tolerance);
    // The tracked poses at `step` of kDt (time step * kDt).
    void setInput(int step);
    StepReport step() { return stepBy(kDt); }
    StepReport stepBy(double dt_s);
    [[nodiscard]] Sample sample() const;
    [[nodiscard]] const Simulation& simulation() const { return model_.simulation; }
    [[nodiscard]] SolverSettings& solver() { return model_.simulation.settings(); }
    [[nodiscard]] int table() const { return table_; }
    [[nodiscard]] int distalBody() const { return model_.bones.back().body; }

  private:
    HandModel model_;
    ElasticTracking tracking_;
    int table_{0};
    std::vector<BonePose> build_;
    std::vector<BonePose> poses_;
};

}  // namespace haptic::softhand::bench
