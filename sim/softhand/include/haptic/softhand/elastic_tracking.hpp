#pragma once

// Elastic tracking through an intermediate skeleton (docs/algorithms.md §2.3, thesis §3.2.6).
// The tracked bone poses may break the joints, jitter, or sit inside objects. Instead of
// pulling the simulated bones to them directly, a rigid-only copy of the skeleton (same
// bodies and soft joints, no tissue, no contact) is synchronised with the simulated bones,
// then moved towards the tracked poses by a few regularised Gauss-Newton steps. Its poses
// are the targets of the simulated bones' tracking springs (U_crb). The result always
// respects the joints, and a blocked hand lags instead of being torn through an object.

#include <span>
#include <string>
#include <vector>

#include "haptic/softhand/hand_builder.hpp"

namespace haptic::softhand {

struct BonePose {
    Vec3 position_m{Vec3::Zero()};
    Mat3 rotation{Mat3::Identity()};
};

struct TrackingSettings {
    double linear_stiffness_n_per_m{500.0};    // k_l: intermediate bone -> tracked bone
    double angular_stiffness_nm_per_rad{0.5};  // k_r
    int gauss_newton_iterations{3};
    double max_target_speed_m_per_s{1.5};  // per step; faster input is clamped
};

class ElasticTracking {
  public:
    // Call right after buildHand (the model must still be in its build pose).
    ElasticTracking(const HandModel& model, TrackingSettings settings = {});

    // One pose per bone of model.bones, same order. Refuses non-finite poses or non-rotations
    // (the previous input stays); the reason is returned through `reason`.
    bool setTrackedPoses(std::span<const BonePose> poses, std::string* reason);

    // Before each simulation step: sync, move towards the tracked poses, set the targets.
    // Returns true when the target speed clamp engaged.
    bool update(HandModel& model, double dt_s);

    // After the model was moved as a whole (SceneSimulation::reset): the current bone poses
    // become the tracked poses and the rate clamp's reference.
    void resetToModel(const HandModel& model);

    [[nodiscard]] const std::vector<BonePose>& trackedPoses() const { return tracked_; }
    [[nodiscard]] BonePose intermediatePose(int bone) const;

  private:
    TrackingSettings settings_;
    Simulation skeleton_;
    std::vector<int> bodies_;  // skeleton_ body per bone
    std::vector<BonePose> tracked_;
    std::vector<BonePose> previous_target_;
};

}  // namespace haptic::softhand
