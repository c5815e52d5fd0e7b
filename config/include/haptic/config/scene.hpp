#pragma once

// One YAML file per scene (config/scenes/*.yaml): what handsim simulates, how the hand is
// driven, and which simulated finger each device is attached to. World frame: z up, metres.

#include <algorithm>
#include <array>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "haptic/config/enums.hpp"
#include "haptic/config/types.hpp"

namespace haptic::config {

// How much of the hand is simulated as soft tissue.
enum class HandModel { kFingertip, kFinger, kHand };

template <>
struct EnumTraits<HandModel> {
    static constexpr std::array<EnumEntry<HandModel>, 3> kEntries{{
        {"fingertip", HandModel::kFingertip},
        {"finger", HandModel::kFinger},
        {"hand", HandModel::kHand},
    }};
};

enum class Finger { kThumb, kIndex, kMiddle, kRing, kLittle };

template <>
struct EnumTraits<Finger> {
    static constexpr std::array<EnumEntry<Finger>, 5> kEntries{{
        {"thumb", Finger::kThumb},
        {"index", Finger::kIndex},
        {"middle", Finger::kMiddle},
        {"ring", Finger::kRing},
        {"little", Finger::kLittle},
    }};
};

// YAML: anthropometry: {hand_length_m, hand_breadth_m, fingertip_diameter_m}. The hand
// model builder scales a template hand from these.
struct Anthropometry {
    double hand_length_m{0.0};         // wrist crease to tip of the middle finger
    double hand_breadth_m{0.0};        // across the metacarpal heads
    double fingertip_diameter_m{0.0};  // of the simulated finger(s), at the distal phalanx
};

// YAML: hand: {model, finger (fingertip and finger models only), fingers (hand model only),
//              resolution, anthropometry}
struct HandConfig {
    HandModel model{HandModel::kFinger};
    std::optional<Finger> finger;  // the simulated finger; nullopt for the whole hand
    // The hand model's fingers on its palm; empty = all five. A pinch needs only thumb and
    // index, at less than half the cost of the whole hand.
    std::vector<Finger> fingers;
    int resolution{2};  // mesh refinement level, 0 (coarse) .. 8 (fine)
    Anthropometry anthropometry;

    // Whether a device bound to `f` has a simulated finger to attach to.
    [[nodiscard]] bool simulates(Finger f) const noexcept {
        if (model == HandModel::kHand) {
            return fingers.empty() || std::find(fingers.begin(), fingers.end(), f) != fingers.end();
        }
        return finger == f;
    }
};

enum class ShapeType { kPlane, kBox, kSphere, kCapsule };

template <>
struct EnumTraits<ShapeType> {
    static constexpr std::array<EnumEntry<ShapeType>, 4> kEntries{{
        {"plane", ShapeType::kPlane},
        {"box", ShapeType::kBox},
        {"sphere", ShapeType::kSphere},
        {"capsule", ShapeType::kCapsule},
    }};
};

// Shapes in the object's frame. A plane is the object's z = 0 plane, solid below; it is
// always static. A capsule's axis is the object's z axis.
struct PlaneShape {
    friend bool operator==(const PlaneShape&, const PlaneShape&) = default;
};
struct BoxShape {
    Vec3 half_extents_m{};
    friend bool operator==(const BoxShape&, const BoxShape&) = default;
};
struct SphereShape {
    double radius_m{0.0};
    friend bool operator==(const SphereShape&, const SphereShape&) = default;
};
struct CapsuleShape {
    double radius_m{0.0};
    double half_height_m{0.0};  // of the cylindrical part
    friend bool operator==(const CapsuleShape&, const CapsuleShape&) = default;
};
using Shape = std::variant<PlaneShape, BoxShape, SphereShape, CapsuleShape>;

// YAML: objects: [{name, shape, pose: {position_m, rpy_deg}, <size keys of the shape>,
//                  mass_kg (not for planes), friction}]
struct SceneObject {
    std::string name;
    Shape shape;
    Pose pose;             // object frame in the world frame
    double mass_kg{0.0};   // 0 = static (fixed in the world)
    double friction{0.5};  // Coulomb coefficient

    [[nodiscard]] ShapeType shapeType() const noexcept {
        return static_cast<ShapeType>(shape.index());
    }
    [[nodiscard]] bool isStatic() const noexcept { return mass_kg == 0.0; }
};

// Where HandPose comes from.
enum class TrackingSource { kScripted, kReplay, kTopic };

template <>
struct EnumTraits<TrackingSource> {
    static constexpr std::array<EnumEntry<TrackingSource>, 3> kEntries{{
        {"scripted", TrackingSource::kScripted},
        {"replay", TrackingSource::kReplay},
        {"topic", TrackingSource::kTopic},
    }};
};

// Built-in motions for demos and tests without a tracker.
enum class TrackingScript {
    kPressSlideEdge,      // press on the target's top face, slide across it and over an edge
    kGraspLiftPlacePush,  // pinch the target box, lift it, set it down, push it along +x
};

template <>
struct EnumTraits<TrackingScript> {
    static constexpr std::array<EnumEntry<TrackingScript>, 2> kEntries{{
        {"press_slide_edge", TrackingScript::kPressSlideEdge},
        {"grasp_lift_place_push", TrackingScript::kGraspLiftPlacePush},
    }};
};

// YAML: tracking: {source, ...}. Allowed keys depend on the source:
//   scripted: script, target_object, loop      replay: replay_file, loop      topic: topic
struct TrackingConfig {
    TrackingSource source{TrackingSource::kScripted};
    TrackingScript script{TrackingScript::kPressSlideEdge};  // scripted
    std::string target_object;                               // scripted: an object's name
    std::filesystem::path replay_file;                       // replay: absolute
    std::string topic;                                       // topic: DDS topic of HandPose
    // topic: no valid pose for this long and handsim withholds its device outputs, so that
    // hapticd fades the force instead of rendering a frozen hand for ever.
    int timeout_ms{100};
    bool loop{true};  // scripted, replay
};

// YAML: devices: {<device name>: {finger}}
struct DeviceBinding {
    Finger finger{Finger::kIndex};
};

// YAML: solver: {newton_iterations, pcg_max_iterations, helper_thread}. handsim's per-step
// solver budget,
// chosen per scene because the budget is 1/rate_hz: a 100 Hz finger can afford to
// re-linearise a stiff contact once more, a 200 Hz fingertip cannot. The trade is measured in
// docs/benchmarks.md ("handsim's limits"). Omitted keys keep these defaults.
struct SolverLimits {
    // Newton iterations per step. Under handsim's limits those beyond the first are spent only
    // on steps that still raise the energy (docs/algorithms.md §2.6).
    int newton_iterations{1};
    int pcg_max_iterations{30};  // per Newton iteration
    // A second thread takes the step's fallback solve and next line-search points, on a
    // machine with two or more cores (softhand::HelperThread; the same steps, the slowest
    // shorter where it pays: docs/benchmarks.md). Off: the step runs on handsim's thread alone.
    bool helper_thread{false};

    friend bool operator==(const SolverLimits&, const SolverLimits&) = default;
};

struct SceneConfig {
    std::filesystem::path source;
    std::string name;
    int rate_hz{100};  // intended 60-200 Hz; 1-1000 is accepted for tests and slow machines
    HandConfig hand;
    std::vector<SceneObject> objects;  // names unique
    TrackingConfig tracking;
    std::map<std::string, DeviceBinding, std::less<>> devices;  // by device name
    SolverLimits solver;

    [[nodiscard]] const SceneObject* findObject(std::string_view object_name) const noexcept {
        for (const auto& object : objects) {
            if (object.name == object_name) {
                return &object;
            }
        }
        return nullptr;
    }
};

// Loads and validates one scene file. Throws ConfigError.
[[nodiscard]] SceneConfig loadSceneConfig(const std::filesystem::path& path);

}  // namespace haptic::config
