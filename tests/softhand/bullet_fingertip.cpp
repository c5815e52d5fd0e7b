#include "bullet_fingertip.hpp"

#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <BulletSoftBody/btDeformableBodySolver.h>
#include <BulletSoftBody/btDeformableGravityForce.h>
#include <BulletSoftBody/btDeformableLinearElasticityForce.h>
#include <BulletSoftBody/btDeformableMultiBodyConstraintSolver.h>
#include <BulletSoftBody/btDeformableMultiBodyDynamicsWorld.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

namespace haptic::softhand::bench {

namespace {

btVector3 toBt(const Vec3& v) {
    return {static_cast<btScalar>(v.x()), static_cast<btScalar>(v.y()),
            static_cast<btScalar>(v.z())};
}

// The solver's Krylov iteration cap is a protected member with no setter.
class CappedDeformableSolver : public btDeformableBodySolver {
  public:
    void setIterationCap(int iterations) {
        m_cg.m_maxIterations = iterations;
        m_cr.m_maxIterations = iterations;
    }
    void setNewtonIterations(int iterations) { m_maxNewtonIterations = iterations; }
};

// The table is a heavy, gravity-free dynamic body reset after every step: Bullet applies each
// contact impulse to it as well (static bodies take none), so its velocity change is the
// impulse the tissue gave it.
constexpr btScalar kTableMassKg = 1000.0;
constexpr btScalar kTableHalfThicknessM = 0.01;

}  // namespace

struct BulletFingertip::World {
    btSoftBodyRigidBodyCollisionConfiguration configuration;
    btCollisionDispatcher dispatcher{&configuration};
    btDbvtBroadphase broadphase;
    CappedDeformableSolver deformable_solver;
    btDeformableMultiBodyConstraintSolver constraint_solver;
    std::unique_ptr<btDeformableMultiBodyDynamicsWorld> world;
    btBoxShape table_shape{btVector3(0.05, 0.05, kTableHalfThicknessM)};
    std::unique_ptr<btRigidBody> table;
    btTransform table_pose;
    btSphereShape bone_shape{0.001};
    std::unique_ptr<btDefaultMotionState> bone_motion;
    std::unique_ptr<btRigidBody> bone;
    std::unique_ptr<btSoftBody> tissue;
    std::unique_ptr<btDeformableGravityForce> gravity;
    std::unique_ptr<btDeformableLinearElasticityForce> elasticity;
    std::vector<btVector3> previous_velocity;
    Vec3 bone_rest{Vec3::Zero()};
    std::vector<Vec3> rest;
    BoneDrive drive{BoneDrive::kTracked};
    Vec3 target{Vec3::Zero()};
    double tracking_linear{0.0};
    double tracking_angular{0.0};

    ~World() {
        if (world) {
            world->removeSoftBody(tissue.get());
            world->removeRigidBody(bone.get());
            world->removeRigidBody(table.get());
        }
        world.reset();
    }
};

BulletFingertip::BulletFingertip(const FingertipModel& model, const SolverSettings& solver,
                                 const BulletSettings& settings)
    : world_(std::make_unique<World>()) {
    World& w = *world_;
    w.drive = settings.drive;
    w.tracking_linear = model.tracking_linear_n_per_m;
    w.tracking_angular = model.tracking_angular_nm_per_rad;
    w.target = model.bone_position_m;
    w.bone_rest = model.bone_position_m;
    w.rest = model.mesh.nodes_m;
    w.deformable_solver.setIterationCap(settings.krylov_iterations);
    w.deformable_solver.setNewtonIterations(settings.newton_iterations);
    w.deformable_solver.setImplicit(settings.implicit);
    w.deformable_solver.setLineSearch(false);
    w.constraint_solver.setDeformableSolver(&w.deformable_solver);
    w.world = std::make_unique<btDeformableMultiBodyDynamicsWorld>(
        &w.dispatcher, &w.broadphase, &w.constraint_solver, &w.configuration, &w.deformable_solver);
    btDeformableMultiBodyDynamicsWorld& world = *w.world;
    world.setImplicit(settings.implicit);
    // Bullet's Newton loop solves without the contact Lagrange multipliers, so its implicit
    // scheme needs the projection form of the contacts (and CG instead of CR).
    world.setUseProjection(settings.implicit);
    w.deformable_solver.m_useProjection = settings.implicit;
    world.setLineSearch(false);
    const btVector3 gravity = toBt(solver.gravity_m_per_s2);
    world.setGravity(gravity);
    world.getWorldInfo().m_gravity = gravity;
    world.getWorldInfo().m_sparsesdf.setDefaultVoxelsz(static_cast<btScalar>(settings.sdf_voxel_m));
    world.getWorldInfo().m_sparsesdf.Reset();

    // Table: top face at kTableHeightM.
    w.table_shape.setMargin(static_cast<btScalar>(settings.collision_margin_m * 0.5));
    btVector3 table_inertia;
    w.table_shape.calculateLocalInertia(kTableMassKg, table_inertia);
    w.table_pose.setIdentity();
    w.table_pose.setOrigin(btVector3(0.0, 0.0, kTableHeightM - kTableHalfThicknessM));
    btRigidBody::btRigidBodyConstructionInfo table_info(kTableMassKg, nullptr, &w.table_shape,
                                                        table_inertia);
    table_info.m_startWorldTransform = w.table_pose;
    table_info.m_friction = static_cast<btScalar>(kTableFriction);
    w.table = std::make_unique<btRigidBody>(table_info);
    w.table->setFlags(w.table->getFlags() | BT_DISABLE_WORLD_GRAVITY);
    w.table->setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(w.table.get());
    w.table->setGravity(btVector3(0, 0, 0));

    // Bone: rigid, in no collision pair (mask 0); Rayleigh alpha as Bullet's per-second damping.
    btTransform bone_pose;
    bone_pose.setIdentity();
    bone_pose.setOrigin(toBt(model.bone_position_m));
    w.bone_motion = std::make_unique<btDefaultMotionState>(bone_pose);
    const bool kinematic = settings.drive == BoneDrive::kKinematic;
    btRigidBody::btRigidBodyConstructionInfo bone_info(
        kinematic ? 0.0 : static_cast<btScalar>(model.bone_mass_kg), w.bone_motion.get(),
        &w.bone_shape, kinematic ? btVector3(0, 0, 0) : toBt(model.bone_inertia_kg_m2));
    w.bone = std::make_unique<btRigidBody>(bone_info);
    const auto damping = static_cast<btScalar>(1.0 - std::exp(-solver.mass_damping_per_s));
    w.bone->setDamping(damping, damping);
    w.bone->setActivationState(DISABLE_DEACTIVATION);
    if (kinematic) {
        w.bone->setCollisionFlags(w.bone->getCollisionFlags() |
                                  btCollisionObject::CF_KINEMATIC_OBJECT);
    }
    world.addRigidBody(w.bone.get(), btBroadphaseProxy::DefaultFilter, 0);

    // Tissue: our nodes, lumped masses (rho V / 4 per tetrahedron, as the soft hand) and tets.
    const std::size_t n = model.mesh.nodes_m.size();
    std::vector<btVector3> x(n);
    std::vector<btScalar> mass(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        x[i] = toBt(model.mesh.nodes_m[i]);
    }
    for (const auto& t : model.mesh.tets) {
        const auto& p = model.mesh.nodes_m;
        const double volume = signedVolume(p[t[0]], p[t[1]], p[t[2]], p[t[3]]);
        for (int c = 0; c < 4; ++c) {
            mass[static_cast<std::size_t>(t[c])] +=
                static_cast<btScalar>(0.25 * model.material.density_kg_per_m3 * volume);
        }
    }
    w.tissue = std::make_unique<btSoftBody>(&world.getWorldInfo(), static_cast<int>(n), x.data(),
                                            mass.data());
    btSoftBody& psb = *w.tissue;
    // Bullet builds its node tree bottom-up from link adjacency: without the edges as links
    // it never finishes. Links carry no force in the deformable world (none is added here).
    std::set<std::pair<int, int>> edges;
    for (const auto& t : model.mesh.tets) {
        psb.appendTetra(t[0], t[1], t[2], t[3]);
        for (int a = 0; a < 4; ++a) {
            for (int b = a + 1; b < 4; ++b) {
                edges.emplace(std::min(t[a], t[b]), std::max(t[a], t[b]));
            }
        }
    }
    for (const auto& [a, b] : edges) {
        psb.appendLink(a, b, nullptr, false);
    }
    psb.initializeDmInverse();
    btSoftBody::TetraScratch rest;  // the rest state, so no scratch starts uninitialised
    rest.m_F.setIdentity();
    rest.m_trace = 3;
    rest.m_J = 1;
    rest.m_cofF.setIdentity();
    rest.m_corotation.setIdentity();
    psb.m_tetraScratches.resize(psb.m_tetras.size(), rest);
    psb.m_tetraScratchesTn.resize(psb.m_tetras.size(), rest);
    btSoftBodyHelpers::generateBoundaryFaces(&psb);
    psb.getCollisionShape()->setMargin(static_cast<btScalar>(settings.collision_margin_m));
    psb.m_cfg.kDF = 1.0;  // Bullet's friction is kDF * the body's friction
    psb.m_cfg.kCHR = 1.0;
    psb.m_cfg.kKHR = 1.0;
    // Node-vs-rigid contacts (SDF_RDN; SDF_RD alone generates none in 3.24), as the soft
    // hand's contacts are per skin node.
    psb.m_cfg.collisions = btSoftBody::fCollision::SDF_RD | btSoftBody::fCollision::SDF_RDN;
    psb.m_sleepingThreshold = 0;
    world.addSoftBody(&psb);
    w.gravity = std::make_unique<btDeformableGravityForce>(gravity);
    world.addForce(&psb, w.gravity.get());
    const double e = model.material.youngs_modulus_pa;
    const double nu = model.material.poisson_ratio;
    const double mu = e / (2.0 * (1.0 + nu));
    const double lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    // Bullet's alpha / beta are the same Rayleigh terms: -alpha M v and beta times the
    // elastic stress rate (its damping stress uses beta * mu and beta * lambda).
    w.elasticity = std::make_unique<btDeformableLinearElasticityForce>(
        static_cast<btScalar>(mu), static_cast<btScalar>(lambda),
        static_cast<btScalar>(solver.mass_damping_per_s),
        static_cast<btScalar>(solver.stiffness_damping_s));
    world.addForce(&psb, w.elasticity.get());
    for (int node : model.bone_nodes) {
        psb.appendDeformableAnchor(node, w.bone.get());
    }
}

BulletFingertip::~BulletFingertip() = default;

void BulletFingertip::setBoneTarget(const Vec3& position_m) {
    world_->target = position_m;
}

void BulletFingertip::step(double dt_s) {
    World& w = *world_;
    if (w.drive == BoneDrive::kKinematic) {
        btTransform pose;
        pose.setIdentity();
        pose.setOrigin(toBt(w.target));
        w.bone_motion->setWorldTransform(pose);
    } else {
        const btTransform& pose = w.bone->getWorldTransform();
        const btVector3 offset = toBt(w.target) - pose.getOrigin();
        w.bone->applyCentralForce(static_cast<btScalar>(w.tracking_linear) * offset);
        const btQuaternion q = pose.getRotation();
        w.bone->applyTorque(static_cast<btScalar>(-w.tracking_angular) * q.getAngle() *
                            q.getAxis());
    }
    w.previous_velocity.resize(static_cast<std::size_t>(w.tissue->m_nodes.size()));
    for (int i = 0; i < w.tissue->m_nodes.size(); ++i) {
        w.previous_velocity[static_cast<std::size_t>(i)] = w.tissue->m_nodes[i].m_v;
    }
    dt_s_ = dt_s;
    w.world->stepSimulation(static_cast<btScalar>(dt_s), 0);
    table_force_z_ = static_cast<double>(kTableMassKg * w.table->getLinearVelocity().z()) / dt_s;
    w.table->setLinearVelocity(btVector3(0, 0, 0));
    w.table->setAngularVelocity(btVector3(0, 0, 0));
    w.table->setWorldTransform(w.table_pose);
    w.table->setInterpolationWorldTransform(w.table_pose);
}

double BulletFingertip::transmittedForceZ() {
    World& w = *world_;
    btSoftBody& psb = *w.tissue;
    if (dt_s_ <= 0.0) {
        return 0.0;
    }
    psb.updateDeformation();  // elastic state at the end of the step (Bullet's is at m_q)
    btAlignedObjectArray<btVector3> force;
    force.resize(psb.m_nodes.size(), btVector3(0, 0, 0));
    w.elasticity->addScaledForces(1.0, force);  // elastic + Rayleigh damping
    const btVector3 gravity = w.world->getWorldInfo().m_gravity;
    double from_table = 0.0;
    for (int i = 0; i < psb.m_nodes.size(); ++i) {
        const btSoftBody::Node& n = psb.m_nodes[i];
        if (n.m_battach != 0 || n.m_im <= 0) {
            continue;
        }
        const double mass = 1.0 / static_cast<double>(n.m_im);
        const double dv = static_cast<double>(n.m_v.z()) -
                          static_cast<double>(w.previous_velocity[static_cast<std::size_t>(i)].z());
        from_table += mass * dv / dt_s_ - static_cast<double>(force[n.index].z()) -
                      mass * static_cast<double>(gravity.z());
    }
    return -from_table;
}

double BulletFingertip::maxDistortion() const {
    const Vec3 shift = bonePosition() - world_->bone_rest;
    double worst = 0.0;
    for (int i = 0; i < world_->tissue->m_nodes.size(); ++i) {
        worst = std::max(
            worst, (nodePosition(i) - world_->rest[static_cast<std::size_t>(i)] - shift).norm());
    }
    return worst;
}

Vec3 BulletFingertip::bonePosition() const {
    const btVector3& p = world_->bone->getWorldTransform().getOrigin();
    return {p.x(), p.y(), p.z()};
}

int BulletFingertip::nodeCount() const {
    return world_->tissue->m_nodes.size();
}

int BulletFingertip::tetCount() const {
    return world_->tissue->m_tetras.size();
}

double BulletFingertip::tissueVolume() const {
    double volume = 0.0;
    for (int i = 0; i < world_->tissue->m_tetras.size(); ++i) {
        volume += world_->tissue->m_tetras[i].m_element_measure;
    }
    return volume;
}

double BulletFingertip::tissueMass() const {
    double mass = 0.0;
    for (int i = 0; i < world_->tissue->m_nodes.size(); ++i) {
        mass += world_->tissue->getMass(i);
    }
    return mass;
}

int BulletFingertip::anchorCount() const {
    return world_->tissue->m_deformableAnchors.size();
}

Vec3 BulletFingertip::nodePosition(int node) const {
    const btVector3& p = world_->tissue->m_nodes[node].m_x;
    return {p.x(), p.y(), p.z()};
}

bool BulletFingertip::finite() const {
    // A node 1 cm from where the bone's rigid motion would put it: the 16 mm pad has
    // collapsed or blown up, finite or not (the soft hand's rows stay under 6 mm).
    constexpr double kDistortionLimitM = 0.01;
    return std::isfinite(table_force_z_) && bonePosition().allFinite() &&
           maxDistortion() < kDistortionLimitM;
}

}  // namespace haptic::softhand::bench
