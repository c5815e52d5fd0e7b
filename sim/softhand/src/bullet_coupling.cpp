#include "haptic/softhand/bullet_coupling.hpp"

#include <btBulletDynamicsCommon.h>

#include <variant>

namespace haptic::softhand {

namespace {

// Debian's Bullet is built with float btScalar.
btScalar scalar(double v) {
    return static_cast<btScalar>(v);
}

btVector3 toBt(const Vec3& v) {
    return {scalar(v.x()), scalar(v.y()), scalar(v.z())};
}
Vec3 fromBt(const btVector3& v) {
    return {v.x(), v.y(), v.z()};
}

btMatrix3x3 toBt(const Mat3& r) {
    return {scalar(r(0, 0)), scalar(r(0, 1)), scalar(r(0, 2)), scalar(r(1, 0)), scalar(r(1, 1)),
            scalar(r(1, 2)), scalar(r(2, 0)), scalar(r(2, 1)), scalar(r(2, 2))};
}

Mat3 fromBt(const btMatrix3x3& r) {
    Mat3 out;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            out(i, j) = r[i][j];
        }
    }
    return out;
}

Vec3 toEigen(const config::Vec3& v) {
    return {v[0], v[1], v[2]};
}

}  // namespace

Mat3 rotationFromRpy(const config::Vec3& rpy) {
    return (Eigen::AngleAxisd(rpy[2], Vec3::UnitZ()) * Eigen::AngleAxisd(rpy[1], Vec3::UnitY()) *
            Eigen::AngleAxisd(rpy[0], Vec3::UnitX()))
        .toRotationMatrix();
}

struct BulletCoupling::Engine {
    btDefaultCollisionConfiguration configuration;
    btCollisionDispatcher dispatcher{&configuration};
    btDbvtBroadphase broadphase;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &configuration};
    std::vector<std::unique_ptr<btCollisionShape>> shapes;
    std::vector<std::unique_ptr<btDefaultMotionState>> motion_states;
    std::vector<std::unique_ptr<btRigidBody>> bodies;

    ~Engine() {
        for (auto& body : bodies) {
            world.removeRigidBody(body.get());
        }
    }
};

BulletCoupling::BulletCoupling(const std::vector<config::SceneObject>& objects, Simulation& sim,
                               EngineCouplingSettings settings)
    : settings_(settings), engine_(std::make_unique<Engine>()) {
    engine_->world.setGravity(toBt(settings_.gravity_m_per_s2));
    engine_->world.setInternalTickCallback(
        [](btDynamicsWorld* world, btScalar) {
            static_cast<BulletCoupling*>(world->getWorldUserInfo())->applySpringWrenches();
        },
        this, true);
    for (const auto& object : objects) {
        struct ShapeVisitor {
            std::unique_ptr<btCollisionShape> operator()(const config::PlaneShape&) const {
                return std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), btScalar(0));
            }
            std::unique_ptr<btCollisionShape> operator()(const config::BoxShape& b) const {
                return std::make_unique<btBoxShape>(toBt(toEigen(b.half_extents_m)));
            }
            std::unique_ptr<btCollisionShape> operator()(const config::SphereShape& s) const {
                return std::make_unique<btSphereShape>(scalar(s.radius_m));
            }
            std::unique_ptr<btCollisionShape> operator()(const config::CapsuleShape& c) const {
                return std::make_unique<btCapsuleShapeZ>(scalar(c.radius_m),
                                                         scalar(2.0 * c.half_height_m));
            }
        };
        const Vec3 position = toEigen(object.pose.position_m);
        const Mat3 rotation = rotationFromRpy(object.pose.rpy_rad);
        auto shape = std::visit(ShapeVisitor{}, object.shape);
        const bool dynamic = !object.isStatic() && object.shapeType() != config::ShapeType::kPlane;
        const double mass = dynamic ? object.mass_kg : 0.0;
        btVector3 inertia(0, 0, 0);
        if (dynamic) {
            shape->calculateLocalInertia(scalar(mass), inertia);
        }
        auto motion =
            std::make_unique<btDefaultMotionState>(btTransform(toBt(rotation), toBt(position)));
        btRigidBody::btRigidBodyConstructionInfo info(scalar(mass), motion.get(), shape.get(),
                                                      inertia);
        info.m_friction = scalar(object.friction);
        auto body = std::make_unique<btRigidBody>(info);
        if (dynamic) {
            body->setActivationState(DISABLE_DEACTIVATION);  // the hand may push it any time
        }
        engine_->world.addRigidBody(body.get());

        Object entry;
        entry.engine_index = static_cast<int>(engine_->bodies.size());
        ColliderDesc collider{colliderShape(object), position, rotation, object.friction, -1};
        if (dynamic) {
            RigidBodyDesc duplicate;
            duplicate.mass_kg = mass;
            duplicate.inertia_body_kg_m2 = fromBt(inertia).asDiagonal();
            duplicate.position_m = position;
            duplicate.rotation = rotation;
            duplicate.gravity = false;  // gravity lives in the engine only (§2.5 step 4)
            entry.duplicate = sim.addBody(duplicate);
            sim.setTrackingStiffness(entry.duplicate, settings_.linear_stiffness_n_per_m,
                                     settings_.angular_stiffness_nm_per_rad);
            collider.body = entry.duplicate;
            entry.duplicate_position = position;
            entry.duplicate_rotation = rotation;
        }
        entry.collider = sim.addCollider(collider);
        engine_->shapes.push_back(std::move(shape));
        engine_->motion_states.push_back(std::move(motion));
        engine_->bodies.push_back(std::move(body));
        objects_.push_back(entry);
    }
}

BulletCoupling::~BulletCoupling() = default;

void BulletCoupling::applySpringWrenches() {
    for (const auto& object : objects_) {
        if (object.duplicate < 0) {
            continue;
        }
        btRigidBody& body = *engine_->bodies[object.engine_index];
        const Vec3 engine_c = fromBt(body.getCenterOfMassPosition());
        const Mat3 engine_r = fromBt(body.getWorldTransform().getBasis());
        // The spring pulls the duplicate towards the engine body; the engine body gets the
        // opposite wrench, so the hand's push reaches Bullet. Bullet accumulates forces over
        // its substeps and adds gravity once per stepSimulation, so each substep starts over
        // from gravity alone.
        const Vec3 force =
            settings_.linear_stiffness_n_per_m * (object.duplicate_position - engine_c);
        const Vec3 torque = settings_.angular_stiffness_nm_per_rad *
                            logMap(object.duplicate_rotation * engine_r.transpose());
        body.clearForces();
        body.applyGravity();
        body.applyCentralForce(toBt(force));
        body.applyTorque(toBt(torque));
    }
}

void BulletCoupling::exchange(Simulation& sim, double dt_s) {
    // The duplicates' poses after the hand step hold for the engine step. The spring on the
    // engine side is explicit, so it is re-evaluated at every engine substep (pre-tick
    // callback) from the body's current pose: stable while k/m (dt/substeps)^2 < 4, not
    // k/m dt^2 < 4 (a 30 g box at 60 Hz is beyond the latter).
    for (auto& object : objects_) {
        if (object.duplicate >= 0) {
            object.duplicate_position = sim.bodyPosition(object.duplicate);
            object.duplicate_rotation = sim.bodyRotation(object.duplicate);
        }
    }
    const double engine_dt = dt_s / settings_.engine_substeps;
    last_engine_dt_s_ = engine_dt;
    engine_->world.stepSimulation(scalar(dt_s), settings_.engine_substeps, scalar(engine_dt));
    for (const auto& object : objects_) {
        if (object.duplicate >= 0) {
            sim.setTrackingTarget(object.duplicate,
                                  enginePosition(static_cast<int>(&object - objects_.data())),
                                  engineRotation(static_cast<int>(&object - objects_.data())));
        }
    }
}

Vec3 BulletCoupling::enginePosition(int object) const {
    return fromBt(engine_->bodies[objects_[object].engine_index]->getCenterOfMassPosition());
}

Mat3 BulletCoupling::engineRotation(int object) const {
    return fromBt(engine_->bodies[objects_[object].engine_index]->getWorldTransform().getBasis());
}

double BulletCoupling::engineContactForce(int object_a, int object_b) const {
    if (last_engine_dt_s_ <= 0.0) {
        return 0.0;
    }
    const btCollisionObject* a = engine_->bodies[objects_[object_a].engine_index].get();
    const btCollisionObject* b = engine_->bodies[objects_[object_b].engine_index].get();
    btDispatcher& dispatcher = *engine_->world.getDispatcher();
    double impulse = 0.0;
    for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
        const btPersistentManifold& manifold = *dispatcher.getManifoldByIndexInternal(m);
        if (!((manifold.getBody0() == a && manifold.getBody1() == b) ||
              (manifold.getBody0() == b && manifold.getBody1() == a))) {
            continue;
        }
        for (int p = 0; p < manifold.getNumContacts(); ++p) {
            impulse += manifold.getContactPoint(p).getAppliedImpulse();
        }
    }
    return impulse / last_engine_dt_s_;
}

}  // namespace haptic::softhand
