#pragma once

// The fingertip press scene in Bullet's own deformable-body solver (BulletSoftBody,
// btDeformableMultiBodyDynamicsWorld): the same tetrahedra, node masses, co-rotational linear
// elasticity with the same Lame parameters and Rayleigh damping, gravity, a rigid bone with
// the same mass and inertia holding the same nodes (as Bullet deformable anchors), and a
// table with the same friction. Bullet has no penalty contact and no strain limits: contact is
// its velocity-level constraint with friction, which is the point of the comparison.

#include <memory>

#include "fingertip_press_scene.hpp"

namespace haptic::softhand::bench {

enum class BoneDrive {
    // A dynamic rigid body pulled towards the scripted target by the tracking spring (same
    // stiffness as the soft hand's), applied as an external force each step: the same scene.
    kTracked,
    // A kinematic body moved along a given path (the reference's bone trajectory): isolates
    // tissue + contact, since the bone then moves exactly as in the reference.
    kKinematic,
};

struct BulletSettings {
    BoneDrive drive{BoneDrive::kTracked};
    int krylov_iterations{300};  // Bullet's default cap of its CG / CR linear solve
    // Backward Euler with this many Newton iterations; false = Bullet's explicit elasticity
    // (damping implicit only), unstable for this tissue at dt = 5 ms.
    bool implicit{true};
    int newton_iterations{1};
    double sdf_voxel_m{0.002};  // sparse SDF of the table box (a plane: exact at any size)
    double collision_margin_m{0.0002};
};

class BulletFingertip {
  public:
    BulletFingertip(const FingertipModel& model, const SolverSettings& solver,
                    const BulletSettings& settings);
    ~BulletFingertip();
    BulletFingertip(const BulletFingertip&) = delete;
    BulletFingertip& operator=(const BulletFingertip&) = delete;

    // kTracked: the tracking target (world); kKinematic: where the bone centre is after the step.
    void setBoneTarget(const Vec3& position_m);
    void step(double dt_s);
    // Force the tissue exerted on the table over the last step (z, negative = pushing down),
    // from the contact impulses Bullet applied to the table body: m * dv / dt.
    [[nodiscard]] double tableForceZ() const { return table_force_z_; }
    // The same force from the momentum balance of the tissue nodes not held by the bone:
    // -sum(m dv/dt - f_elastic - f_damping - m g) at the end of the last step (the table is
    // the only other thing touching them). Not part of step()'s cost.
    [[nodiscard]] double transmittedForceZ();
    [[nodiscard]] Vec3 bonePosition() const;
    // The table force is the momentum-balance one (see docs/benchmarks.md for why).
    [[nodiscard]] Sample sample() { return {transmittedForceZ(), bonePosition()}; }
    // Largest distance of a node from where the bone's rigid motion would put it (m).
    [[nodiscard]] double maxDistortion() const;
    [[nodiscard]] int nodeCount() const;
    [[nodiscard]] int tetCount() const;
    [[nodiscard]] double tissueVolume() const;  // sum of Bullet's tetra rest volumes
    [[nodiscard]] double tissueMass() const;
    [[nodiscard]] int anchorCount() const;
    [[nodiscard]] Vec3 nodePosition(int node) const;
    // False once anything is non-finite or a node is 1 cm off the bone's rigid motion.
    [[nodiscard]] bool finite() const;

  private:
    struct World;
    std::unique_ptr<World> world_;
    double table_force_z_{0.0};
    double dt_s_{0.0};
};

}  // namespace haptic::softhand::bench
