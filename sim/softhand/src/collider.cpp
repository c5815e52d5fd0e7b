#include "haptic/softhand/collider.hpp"

#include <algorithm>
#include <cmath>

namespace haptic::softhand {

namespace {

SurfaceQuery sphereQuery(const Vec3& center, double radius, const Vec3& p) {
    const Vec3 offset = p - center;
    const double distance = offset.norm();
    // At the exact centre every direction is closest; pick +z so the answer stays defined.
    const Vec3 normal = distance > 1e-12 ? Vec3(offset / distance) : Vec3(Vec3::UnitZ());
    return {distance - radius, normal, center + radius * normal};
}

SurfaceQuery boxQuery(const Box& box, const Vec3& p) {
    const Vec3& h = box.half_extents_m;
    const Vec3 clamped = p.cwiseMax(-h).cwiseMin(h);
    const Vec3 outside = p - clamped;
    const double outside_distance = outside.norm();
    if (outside_distance > 0.0) {
        return {outside_distance, outside / outside_distance, clamped};
    }
    // Inside: the nearest face wins.
    int axis = 0;
    double depth = h.x() - std::abs(p.x());
    for (int a = 1; a < 3; ++a) {
        const double d = h[a] - std::abs(p[a]);
        if (d < depth) {
            depth = d;
            axis = a;
        }
    }
    const double sign = p[axis] >= 0.0 ? 1.0 : -1.0;
    SurfaceQuery q;
    q.phi_m = -depth;
    q.normal = Vec3::Zero();
    q.normal[axis] = sign;
    q.surface_point_m = p;
    q.surface_point_m[axis] = sign * h[axis];
    return q;
}

}  // namespace

SurfaceQuery querySurface(const ColliderShape& shape, const Vec3& p) {
    struct Visitor {
        const Vec3& p;
        SurfaceQuery operator()(const HalfSpace&) const {
            return {p.z(), Vec3::UnitZ(), Vec3(p.x(), p.y(), 0.0)};
        }
        SurfaceQuery operator()(const Box& box) const { return boxQuery(box, p); }
        SurfaceQuery operator()(const Sphere& sphere) const {
            return sphereQuery(Vec3::Zero(), sphere.radius_m, p);
        }
        SurfaceQuery operator()(const Capsule& capsule) const {
            const double z = std::clamp(p.z(), -capsule.half_height_m, capsule.half_height_m);
            return sphereQuery(Vec3(0.0, 0.0, z), capsule.radius_m, p);
        }
    };
    return std::visit(Visitor{p}, shape);
}

ColliderShape colliderShape(const config::SceneObject& object) {
    struct Visitor {
        ColliderShape operator()(const config::PlaneShape&) const { return HalfSpace{}; }
        ColliderShape operator()(const config::BoxShape& b) const {
            return Box{Vec3(b.half_extents_m[0], b.half_extents_m[1], b.half_extents_m[2])};
        }
        ColliderShape operator()(const config::SphereShape& s) const { return Sphere{s.radius_m}; }
        ColliderShape operator()(const config::CapsuleShape& c) const {
            return Capsule{c.radius_m, c.half_height_m};
        }
    };
    return std::visit(Visitor{}, object.shape);
}

}  // namespace haptic::softhand
