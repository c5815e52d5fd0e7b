#include <algorithm>
#include <map>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "haptic/config/scene.hpp"
#include "schema.hpp"

namespace haptic::config {
namespace {

// SceneObject::shapeType() maps the variant index to ShapeType.
static_assert(std::is_same_v<std::variant_alternative_t<0, Shape>, PlaneShape> &&
              std::is_same_v<std::variant_alternative_t<1, Shape>, BoxShape> &&
              std::is_same_v<std::variant_alternative_t<2, Shape>, SphereShape> &&
              std::is_same_v<std::variant_alternative_t<3, Shape>, CapsuleShape> &&
              static_cast<int>(ShapeType::kCapsule) == 3);

using spec::Real;

// Bounds for a human hand (adult 5th to 95th percentile with a wide margin). They exist
// to catch unit mistakes, not to judge anatomy.
constexpr std::size_t kMaxObjects = 64;

HandConfig readHand(MapReader map) {
    HandConfig out;
    out.model = map.required("model", spec::Enum<HandModel>{});
    // Only the single-finger models pick a finger; the whole-hand model simulates all five,
    // so a `finger` there is reported as an unknown key rather than silently ignored.
    if (out.model != HandModel::kHand) {
        out.finger = map.required("finger", spec::Enum<Finger>{});
    } else if (auto field = map.take("fingers")) {
        const ListReader list = field->list(1, 5, "a finger name");
        for (std::size_t i = 0; i < list.size(); ++i) {
            const Field item = list.at(i);
            const Finger finger = item.as(spec::Enum<Finger>{});
            if (std::find(out.fingers.begin(), out.fingers.end(), finger) != out.fingers.end()) {
                item.fail("each finger at most once");
            }
            out.fingers.push_back(finger);
        }
    }
    out.resolution = map.optional("resolution", 2, spec::Integer<int>::closed(0, 8));
    MapReader anthropometry = map.requiredMap("anthropometry");
    out.anthropometry.hand_length_m =
        anthropometry.required("hand_length_m", Real::closed(0.10, 0.30));
    out.anthropometry.hand_breadth_m =
        anthropometry.required("hand_breadth_m", Real::closed(0.05, 0.15));
    out.anthropometry.fingertip_diameter_m =
        anthropometry.optional("fingertip_diameter_m", 0.016, Real::closed(0.008, 0.03));
    anthropometry.finish();
    map.finish();
    return out;
}

Shape readShape(ShapeType type, MapReader& object) {
    const Real size = Real::positive(detail::kMaxPositionM);
    switch (type) {
        case ShapeType::kPlane:
            return PlaneShape{};
        case ShapeType::kBox:
            return BoxShape{object.required("half_extents_m", spec::Reals<3>{size})};
        case ShapeType::kSphere:
            return SphereShape{object.required("radius_m", size)};
        case ShapeType::kCapsule: {
            const double radius = object.required("radius_m", size);
            return CapsuleShape{radius, object.required("half_height_m", size)};
        }
    }
    return PlaneShape{};
}

SceneObject readObject(MapReader object) {
    SceneObject out;
    out.name = object.required("name", spec::Identifier{});
    const ShapeType type = object.required("shape", spec::Enum<ShapeType>{});
    out.pose = detail::readPose(object.requiredMap("pose"));
    // Size keys are asked for per shape, so a radius_m on a box is an unknown key.
    out.shape = readShape(type, object);
    if (type != ShapeType::kPlane) {
        out.mass_kg = object.optional("mass_kg", 0.0, Real::closed(0.0, 100.0));
    }
    out.friction = object.optional("friction", 0.5, Real::closed(0.0, 2.0));
    object.finish();
    return out;
}

std::vector<SceneObject> readObjects(MapReader& root) {
    const ListReader list = root.requiredList("objects", 0, kMaxObjects, "an object map");
    std::vector<SceneObject> objects;
    for (std::size_t i = 0; i < list.size(); ++i) {
        MapReader object = list.at(i).map();
        // Taken early only to point at it later; readObject reports it if it is missing.
        const std::optional<Field> name_field = object.take("name");
        SceneObject parsed = readObject(std::move(object));
        for (std::size_t j = 0; j < objects.size(); ++j) {
            if (objects[j].name == parsed.name) {
                name_field->fail(
                    "a unique object name",
                    "'" + parsed.name + "', already used by objects[" + std::to_string(j) + "]");
            }
        }
        objects.push_back(std::move(parsed));
    }
    return objects;
}

TrackingConfig readTracking(MapReader map, const std::vector<SceneObject>& objects) {
    TrackingConfig out;
    out.source = map.required("source", spec::Enum<TrackingSource>{});
    switch (out.source) {
        case TrackingSource::kScripted: {
            out.script = map.required("script", spec::Enum<TrackingScript>{});
            auto [target, target_field] =
                map.requiredWithField("target_object", spec::Identifier{});
            // Named copy: clang < 16 cannot capture a structured binding in a lambda.
            const std::string& wanted = target;
            const bool exists = std::any_of(objects.begin(), objects.end(),
                                            [&](const SceneObject& o) { return o.name == wanted; });
            if (!exists) {
                target_field.fail("the name of an object in this scene");
            }
            out.target_object = std::move(target);
            out.loop = map.optional("loop", true, spec::Boolean{});
            break;
        }
        case TrackingSource::kReplay:
            out.replay_file = map.required("replay_file", spec::File{});
            out.loop = map.optional("loop", true, spec::Boolean{});
            break;
        case TrackingSource::kTopic:
            out.topic = map.optional("topic", std::string("tracking/hand"), spec::Text{});
            out.timeout_ms = map.optional("timeout_ms", 100, spec::Integer<int>::closed(10, 10000));
            break;
    }
    map.finish();
    return out;
}

std::map<std::string, DeviceBinding, std::less<>> readBindings(MapReader map,
                                                               const HandConfig& hand) {
    std::map<std::string, DeviceBinding, std::less<>> out;
    for (auto& [key, value] : map.takeAll()) {
        // The key is a device name; reuse the identifier rules on the key node itself.
        const std::string name = key.as(spec::Identifier{});
        MapReader binding = value.map();
        auto [finger, finger_field] = binding.requiredWithField("finger", spec::Enum<Finger>{});
        if (!hand.simulates(finger)) {
            finger_field.fail(
                hand.finger ? "the simulated finger '" + std::string(toString(*hand.finger)) +
                                  "' (hand.model is " + std::string(toString(hand.model)) + ")"
                            : std::string("one of the hand's fingers (hand.fingers)"));
        }
        binding.finish();
        out.emplace(name, DeviceBinding{finger});
    }
    map.finish();
    return out;
}

SolverLimits readSolver(MapReader map) {
    SolverLimits out;
    out.newton_iterations =
        map.optional("newton_iterations", out.newton_iterations, spec::Integer<int>::closed(1, 10));
    out.pcg_max_iterations = map.optional("pcg_max_iterations", out.pcg_max_iterations,
                                          spec::Integer<int>::closed(5, 500));
    out.helper_thread = map.optional("helper_thread", out.helper_thread, spec::Boolean{});
    map.finish();
    return out;
}

}  // namespace

SceneConfig loadSceneConfig(const std::filesystem::path& path) {
    MapReader root = MapReader::openFile(path);
    SceneConfig out;
    out.source = path;
    out.name = root.required("name", spec::Identifier{});
    out.rate_hz = root.required("rate_hz", spec::Integer<int>::closed(1, 1000));
    out.hand = readHand(root.requiredMap("hand"));
    out.objects = readObjects(root);
    out.tracking = readTracking(root.requiredMap("tracking"), out.objects);
    if (std::optional<MapReader> bindings = root.optionalMap("devices")) {
        out.devices = readBindings(*std::move(bindings), out.hand);
    }
    if (std::optional<MapReader> solver = root.optionalMap("solver")) {
        out.solver = readSolver(*std::move(solver));
    }
    root.finish();
    return out;
}

}  // namespace haptic::config
