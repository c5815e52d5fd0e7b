#pragma once

// Coupling with Bullet as the external physics engine (docs/algorithms.md §2.5, thesis §3.2.7).
// Bullet owns the objects: gravity, object-object and object-table contact. The hand solve
// holds a rigid duplicate of each dynamic object (same mass and inertia, no gravity: gravity
// acts in Bullet only) tied to Bullet's body by the 6-DoF spring U_co, which is part of the
// implicit hand solve. After each hand step the opposite wrench is applied to Bullet's body
// and Bullet steps; its new pose is the duplicate's spring anchor for the next hand step.
// Static objects (planes, mass 0) are fixed colliders in both worlds.

#include <memory>
#include <vector>

#include "haptic/config/scene.hpp"
#include "haptic/softhand/simulation.hpp"

namespace haptic::softhand {

struct EngineCouplingSettings {
    double linear_stiffness_n_per_m{400.0};  // k_o
    double angular_stiffness_nm_per_rad{0.2};
    Vec3 gravity_m_per_s2{0.0, 0.0, -9.81};
    int engine_substeps{4};  // Bullet steps per hand step
};

class BulletCoupling {
  public:
    // Adds the objects' colliders (and duplicates of the dynamic ones) to `sim`.
    BulletCoupling(const std::vector<config::SceneObject>& objects, Simulation& sim,
                   EngineCouplingSettings settings = {});
    ~BulletCoupling();
    BulletCoupling(const BulletCoupling&) = delete;
    BulletCoupling& operator=(const BulletCoupling&) = delete;

    // After sim.step(dt): wrench on the engine bodies, engine step, new spring anchors.
    void exchange(Simulation& sim, double dt_s);

    [[nodiscard]] int objectCount() const { return static_cast<int>(objects_.size()); }
    [[nodiscard]] int colliderOf(int object) const { return objects_[object].collider; }
    [[nodiscard]] int duplicateOf(int object) const { return objects_[object].duplicate; }
    [[nodiscard]] Vec3 enginePosition(int object) const;
    [[nodiscard]] Mat3 engineRotation(int object) const;
    // Normal force (N) between two objects in Bullet's last substep, from its contact
    // manifolds; 0 when they do not touch.
    [[nodiscard]] double engineContactForce(int object_a, int object_b) const;

  private:
    struct Object {
        int collider{-1};
        int duplicate{-1};  // -1 for static objects
        int engine_index{-1};
        Vec3 duplicate_position{Vec3::Zero()};  // at the last exchange
        Mat3 duplicate_rotation{Mat3::Identity()};
    };
    void applySpringWrenches();
    struct Engine;
    EngineCouplingSettings settings_;
    std::unique_ptr<Engine> engine_;
    std::vector<Object> objects_;
    double last_engine_dt_s_{0.0};
};

// R = Rz(yaw) Ry(pitch) Rx(roll), the scene files' convention.
[[nodiscard]] Mat3 rotationFromRpy(const config::Vec3& rpy_rad);

}  // namespace haptic::softhand
