#pragma once

// The soft hand of one scene, as handsim runs it: the hand built from the scene (only what
// it requires), its objects in Bullet, elastic tracking of the hand pose input, and the
// device outputs. No I/O: the caller supplies hand poses and sends the outputs.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "haptic/config/scene.hpp"
#include "haptic/softhand/bullet_coupling.hpp"
#include "haptic/softhand/device_outputs.hpp"
#include "haptic/softhand/tracking_input.hpp"

namespace haptic::softhand {

struct SceneSimulationSettings {
    SolverSettings solver;
    HandBuildOptions build;
    TrackingSettings tracking;
    EngineCouplingSettings engine;
    KinestheticOutputSettings kinesthetic;
};

// handsim's solver budget: by default PCG capped at 30 iterations and one Newton iteration;
// a line search of at most 2 halvings (6 along a direction solved from zero, docs/algorithms.md
// §2.6), no substeps, and Newton iterations beyond the first only while the step still raises
// the energy. A step whose energy still rises keeps the Newton positions and scales its
// velocities down (StepReport::rescaled_steps); no finite step is frozen. A scene's `solver:`
// block overrides the Newton and PCG counts: the default scene at 100 Hz takes 2 Newton
// iterations. The choices and their measured costs are in docs/benchmarks.md ("Soft hand
// step").
// `physics` (stiffnesses, damping, gravity) with that budget: what realtimeSceneSettings()
// ships, for benchmarks and validation that run their own scenes as handsim would.
// The CPUs this process may run on (its affinity mask).
[[nodiscard]] int usableCores();
[[nodiscard]] SolverSettings withRealtimeLimits(SolverSettings physics,
                                                const config::SolverLimits& limits = {});
[[nodiscard]] SceneSimulationSettings realtimeSceneSettings(
    const config::SolverLimits& limits = {});

// A device the simulation computes outputs for (one of sim.yaml's devices).
struct DeviceRequest {
    std::string name;
    config::Finger finger{config::Finger::kIndex};
    bool kinesthetic{true};                // exoskeleton: ConstraintSet; thimble: ContactSurface
    config::Transform finger_from_device;  // thimble: finger_calibration.T_finger_device
    int max_samples{64};                   // thimble: optimiser.pad_samples
};

// What a scene's builder made: a scene models only what it needs (a fingertip scene the
// distal phalanx, a one-finger scene that finger and the palm), and handsim logs this.
struct SceneSize {
    int nodes{0};
    int tetrahedra{0};
    int joints{0};
    int colliders{0};  // object surfaces the skin is tested against
    std::vector<std::string> bone_names;
};
[[nodiscard]] std::string toString(const SceneSize& size);

class SceneSimulation {
  public:
    // Throws std::invalid_argument (reason in what()) when the scene cannot carry a device.
    SceneSimulation(const config::SceneConfig& scene, const std::vector<DeviceRequest>& devices,
                    const SceneSimulationSettings& settings = {});

    // Moves the whole hand, at rest, to the pose (start of a run; no tracking transient).
    void reset(const HandPoseInput& pose);
    // Tracking input for the next steps. Returns the reason when it is refused (the
    // previous input stays; the next StepReport also says rejected_input).
    std::optional<std::string> setHandPose(const HandPoseInput& pose);
    StepReport step(double dt_s);

    // Outputs for devices[index] (header left to the caller).
    void fill(std::size_t device, msgs::ConstraintSet& out);
    void fill(std::size_t device, msgs::ContactSurface& out) const;

    [[nodiscard]] const HandModel& model() const { return model_; }
    [[nodiscard]] const TrackedHand& trackedHand() const { return *tracked_hand_; }
    [[nodiscard]] const BulletCoupling& coupling() const { return *coupling_; }
    [[nodiscard]] const KinestheticOutput* kinesthetic(std::size_t device) const;
    [[nodiscard]] const TactileOutput* tactile(std::size_t device) const;
    [[nodiscard]] std::string modelName() const;
    [[nodiscard]] SceneSize size() const;

  private:
    HandModel model_;
    std::unique_ptr<TrackedHand> tracked_hand_;
    std::vector<std::optional<KinestheticOutput>> kinesthetic_;
    std::vector<std::optional<TactileOutput>> tactile_;
    std::unique_ptr<ElasticTracking> tracking_;
    std::unique_ptr<BulletCoupling> coupling_;
    std::vector<BonePose> poses_;  // scratch
    std::string pending_rejection_;
    config::HandConfig hand_;
};

}  // namespace haptic::softhand
