#pragma once

// Analytic signed distance of the object shapes the hand touches (planes, boxes, spheres,
// capsules). Shapes live in the object's frame; the simulation moves that frame.

#include <variant>

#include "haptic/config/scene.hpp"
#include "haptic/softhand/rotation.hpp"

namespace haptic::softhand {

struct HalfSpace {};  // the object's z = 0 plane, solid below
struct Box {
    Vec3 half_extents_m{Vec3::Zero()};
};
struct Sphere {
    double radius_m{0.0};
};
struct Capsule {  // axis along the object's z
    double radius_m{0.0};
    double half_height_m{0.0};
};
using ColliderShape = std::variant<HalfSpace, Box, Sphere, Capsule>;

// Closest-surface query in the object frame. phi < 0 inside.
struct SurfaceQuery {
    double phi_m{0.0};
    Vec3 normal{Vec3::UnitZ()};  // outward unit normal at the closest surface point
    Vec3 surface_point_m{Vec3::Zero()};
};

[[nodiscard]] SurfaceQuery querySurface(const ColliderShape& shape, const Vec3& p_object_m);

// The shape of a scene file's object, in its own frame (the object's pose places it).
[[nodiscard]] ColliderShape colliderShape(const config::SceneObject& object);

}  // namespace haptic::softhand
