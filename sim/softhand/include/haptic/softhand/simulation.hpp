#pragma once

// Soft hand simulation core (docs/algorithms.md §2, thesis ch. 3): tissue nodes and rigid bodies
// (bones, object duplicates) advanced together by backward Euler: Newton iterations with an
// Armijo line search on the step's merit, solved by block-Jacobi PCG, and an energy guard
// that substeps or scales velocities down, never freezing a finite step.
//
// Units: SI (m, kg, s, N, Pa). Frames: world, z up. No I/O; bad input is rejected with a
// reason in the step report, never thrown from step().

#include <Eigen/Core>
#include <array>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "haptic/softhand/block_sparse.hpp"
#include "haptic/softhand/collider.hpp"
#include "haptic/softhand/helper_thread.hpp"
#include "haptic/softhand/pcg.hpp"
#include "haptic/softhand/rotation.hpp"
#include "haptic/softhand/sparse_direct.hpp"
#include "haptic/softhand/tet_mesh.hpp"

namespace haptic::softhand {

struct TissueMaterial {
    double youngs_modulus_pa{5.0e4};
    double poisson_ratio{0.45};
    double density_kg_per_m3{1100.0};
    // Strain limits on the singular values of F as a stiff penalty (docs/algorithms.md §2.4.3,
    // DER): k_sl = ratio * E. Values are a starting point, not fitted to finger data.
    bool strain_limits{true};
    double strain_min{0.7};
    double strain_max{1.3};
    double strain_limit_stiffness_ratio{100.0};
};

// How each Newton iteration solves its linear system.
enum class LinearSolver {
    kPcg,         // block-Jacobi PCG, capped and warm-started (pcg.hpp)
    kSparseLdlt,  // Eigen's SimplicialLDLT, exact (sparse_direct.hpp); PCG if it fails
};

struct SolverSettings {
    Vec3 gravity_m_per_s2{0.0, 0.0, -9.81};
    double mass_damping_per_s{2.0};     // Rayleigh alpha
    double stiffness_damping_s{0.002};  // Rayleigh gamma
    LinearSolver linear_solver{LinearSolver::kPcg};
    int pcg_max_iterations{200};
    double pcg_relative_tolerance{1e-4};
    int max_newton_iterations{5};  // per step (or substep)
    // Newton iterations stop once one moves no DoF by more than this over the step and the
    // energy guard passes. Real-time settings make it infinite: the first iterate that
    // passes the guard ends the step.
    double newton_tolerance_m{1e-6};
    int max_backtracks{10};                    // halvings of a Newton step in its line search
    int max_substep_depth{3};                  // on an energy rise, 2^3 = 8 substeps at most
    double max_speed_m_per_s{5.0};             // node and body speed clamp
    double contact_stiffness_n_per_m{2000.0};  // per skin node
    // Per skin node, tangential. Its stick radius mu f_N / k_f is what a node may move sideways
    // before it slips: at 2000 N/m (tens of um) the tracker's filtered jitter made the pad's
    // friction reverse step to step in the closed loop (docs/algorithms.md §2.4.7).
    double friction_stiffness_n_per_m{500.0};
    // A second thread (HelperThread) solves, alongside the warm-started PCG solve, the cold
    // one the step falls back to when the warm direction fails, and evaluates each line
    // search point's next halving alongside it. The steps are the same to the bit; the
    // slowest ones, with a restart and many halvings, shorten on a free core.
    bool use_helper_thread{false};
};

struct RigidBodyDesc {
    double mass_kg{0.01};
    Mat3 inertia_body_kg_m2{Mat3::Identity() * 1e-6};
    Vec3 position_m{Vec3::Zero()};
    Mat3 rotation{Mat3::Identity()};
    bool kinematic{false};  // pose set from outside only; infinite mass in the solve
    bool gravity{true};
};

enum class JointType { kBall, kHinge, kUniversal };

// Soft joint (docs/algorithms.md §2.4.1). Anchors and axes are in each body's local frame at build
// time; the flexion angle is measured about `axis_a_local` relative to the build-time pose.
struct JointDesc {
    JointType type{JointType::kBall};
    int body_a{-1};
    int body_b{-1};
    Vec3 anchor_world_m{Vec3::Zero()};
    Vec3 axis_world{Vec3::UnitY()};   // hinge / flexion axis (world, at build time)
    Vec3 twist_world{Vec3::UnitX()};  // universal joints: the axis whose twist is penalised
    double positional_stiffness_n_per_m{1.0e3};
    double alignment_stiffness_nm_per_rad{1.0};
    double limit_min_rad{-1.0e9};
    double limit_max_rad{1.0e9};
    double limit_stiffness_nm_per_rad{10.0};
    // How far a flexion angle lies past the limits (negative below the minimum), 0 inside.
    [[nodiscard]] double limitViolation(double flexion_rad) const noexcept {
        return flexion_rad > limit_max_rad   ? flexion_rad - limit_max_rad
               : flexion_rad < limit_min_rad ? flexion_rad - limit_min_rad
                                             : 0.0;
    }
};

struct ColliderDesc {
    ColliderShape shape;
    Vec3 position_m{Vec3::Zero()};
    Mat3 rotation{Mat3::Identity()};
    double friction{0.5};
    int body{-1};  // rigid body carrying the shape (object duplicate); -1 = fixed in world
};

// What the solver did in one step(). Every case ends in a finite state; these say how.
struct StepReport {
    bool rejected_input{false};  // an input (target, dt) was refused and the old one kept
    std::string rejection_reason;
    bool clamped{false};  // speed clamp, target-rate clamp, PCG cap, energy rescale or hold
    bool substepped{false};
    int substeps{1};
    int backtracks{0};
    // (Sub)steps whose total energy rose with no substep left: positions took the Newton
    // result and the velocities were scaled down until the rise was gone (also clamped).
    int rescaled_steps{0};
    // (Sub)steps with no finite state to advance to: positions held, velocities zeroed.
    // Only a non-finite input gets here; a finite one never freezes a step.
    int zeroed_steps{0};
    // Warm-started PCG solves that did not descend and were solved again from zero.
    int restarted_solves{0};
    // Jobs the helper thread ran for this step (cold solves, line-search points it evaluated
    // ahead), not those the step took back and did itself.
    int helper_jobs{0};
    // Of those, the ones whose result an attempt at the step used: a cold solve it took, a
    // halving's point taken from the helper (an attempt whose energy rose is then split into
    // substeps, its results with it). A cold solve the helper ran while the warm one
    // succeeded is a job run, not a result used.
    int helper_results_used{0};
    int newton_iterations{0};  // beyond the first, summed over substeps
    int pcg_iterations{0};     // summed over substeps
    bool pcg_capped{false};
    double pcg_relative_residual{0.0};  // of the last solve
    int active_contacts{0};
    int strain_limited_elements{0};
    int inverted_elements{0};
    double energy_j{0.0};  // kinetic + potential after the step
};

class Simulation {
  public:
    explicit Simulation(SolverSettings settings = {});

    // --- building ---
    // Appends the mesh as tissue; returns the index of its first node. Boundary nodes become
    // skin (contact candidates).
    int addTissue(const TetMesh& mesh, const TissueMaterial& material);
    int addBody(const RigidBodyDesc& desc);
    int addJoint(const JointDesc& desc);
    // Couples a node to a body at the node's current position (docs/algorithms.md §2.4.4).
    void attachNode(int node, int body, double stiffness_n_per_m);
    // The same coupling along one direction only (given in the world, carried by the body):
    // holds a node against sliding along `direction` and leaves it free across it.
    void attachNodeAlong(int node, int body, const Vec3& direction_world, double stiffness_n_per_m);
    // Dirichlet condition on the node's axes (x, y, z): they keep their current position.
    void pinNode(int node, std::array<bool, 3> axes = {true, true, true});
    int addCollider(const ColliderDesc& desc);
    // Elastic tracking spring of a body towards its target (docs/algorithms.md §2.3, U_crb).
    void setTrackingStiffness(int body, double linear_n_per_m, double angular_nm_per_rad);

    // --- inputs between steps ---
    // Rejects non-finite or non-rotation targets (reason in the next report).
    bool setTrackingTarget(int body, const Vec3& position_m, const Mat3& rotation);
    void setNodeForce(int node, const Vec3& force_n);
    void setColliderPose(int collider, const Vec3& position_m, const Mat3& rotation);
    void setNodePosition(int node, const Vec3& position_m);
    void setBodyPose(int body, const Vec3& position_m, const Mat3& rotation);
    void setBodyVelocity(int body, const Vec3& linear_m_per_s, const Vec3& angular_rad_per_s);

    // Advances by dt_s (one step, or substeps when the energy guard demands it).
    StepReport step(double dt_s);
    // Quasi-static relaxation for validation: steps of dt_s started from rest (a Newton
    // iteration on the potential, regularised by M/dt^2) until no node or body moves more
    // than tolerance in a step. Returns the steps taken (max_steps if not converged).
    int relax(double dt_s, int max_steps, double displacement_tolerance_m);

    // --- state ---
    [[nodiscard]] int nodeCount() const { return static_cast<int>(x_.size()); }
    [[nodiscard]] int bodyCount() const { return static_cast<int>(bodies_.size()); }
    [[nodiscard]] int tetCount() const { return static_cast<int>(tets_.size()); }
    [[nodiscard]] const Vec3& nodePosition(int node) const { return x_[node]; }
    [[nodiscard]] const Vec3& nodeRestPosition(int node) const { return rest_[node]; }
    [[nodiscard]] const Vec3& nodeVelocity(int node) const { return v_[node]; }
    [[nodiscard]] double nodeMass(int node) const { return node_mass_[node]; }
    [[nodiscard]] const std::vector<int>& skinNodes() const { return skin_; }
    [[nodiscard]] const Vec3& bodyPosition(int body) const { return bodies_[body].c; }
    [[nodiscard]] const Mat3& bodyRotation(int body) const { return bodies_[body].rotation; }
    [[nodiscard]] const Vec3& bodyLinearVelocity(int body) const { return bodies_[body].v; }
    [[nodiscard]] int jointCount() const { return static_cast<int>(joints_.size()); }
    [[nodiscard]] const JointDesc& jointDesc(int joint) const { return joints_[joint].desc; }
    // Force each collider exerts on each skin node in contact after the last step.
    struct ContactForce {
        int node;
        int collider;
        Vec3 force_n;
        bool sliding;  // the friction anchor was dragged this step (Coulomb limit reached)
    };
    [[nodiscard]] const std::vector<ContactForce>& contactForces() const { return contact_forces_; }
    // Sum of contact forces the tissue applies to a collider (reaction, world frame).
    [[nodiscard]] Vec3 forceOnCollider(int collider) const;
    [[nodiscard]] double totalEnergy() const;
    [[nodiscard]] int colliderCount() const { return static_cast<int>(colliders_.size()); }
    // Closest surface of a collider to a world point, at the collider's current pose; the
    // normal and surface point are in the world frame.
    [[nodiscard]] SurfaceQuery queryCollider(int collider, const Vec3& p_world_m) const;
    [[nodiscard]] const SolverSettings& settings() const { return settings_; }
    SolverSettings& settings() { return settings_; }

    // Internal layout, shared with the energy terms (src/).
    struct Tet {
        std::array<int, 4> nodes;
        Mat3 rest_inverse;  // D_m^-1
        double volume_m3;
        double mu;
        double lambda;
        double limit_stiffness;
        double strain_min;
        double strain_max;
        bool strain_limits;
    };
    struct Body {
        double mass;
        Mat3 inertia_body;
        Vec3 c;
        Mat3 rotation;
        Vec3 v{Vec3::Zero()};
        Vec3 w{Vec3::Zero()};
        bool kinematic;
        bool gravity;
        double track_linear{0.0};
        double track_angular{0.0};
        Vec3 target_c;
        Mat3 target_rotation;
    };
    [[nodiscard]] const Body& body(int index) const { return bodies_[index]; }

    struct Joint {
        JointDesc desc;
        Vec3 anchor_a_local;
        Vec3 anchor_b_local;
        Vec3 axis_a_local;
        Vec3 twist_a_local;
        Mat3 rest_relative;  // R_a^T R_b at build time
    };
    struct Attachment {
        int node;
        int body;
        Vec3 offset_local;
        double stiffness;  // N/m
        // Body-frame unit direction of a hold along one direction (attachNodeAlong); zero for
        // an isotropic attachment, whose stiffness needs no rotation per evaluation.
        Vec3 direction_local;
    };
    struct Collider {
        ColliderDesc desc;
        Vec3 offset_local;  // fixed offset of the shape frame in its body frame
        Mat3 rotation_local;
    };
    struct Contact {
        int node;
        int collider;
        // At detection (the prediction), then brought to the end state by updateAnchors.
        Vec3 normal;              // world
        Vec3 anchor_local;        // friction anchor in the collider frame
        double friction_limit_n;  // mu * normal force (lagged one step)
        bool sliding;             // the anchor was dragged at the end of the last step
    };
    struct Anchor {
        Vec3 local;  // collider frame
        bool sliding;
    };
    // Positions of every DoF, the argument of the potential.
    struct Configuration {
        std::vector<Vec3> x;
        std::vector<Vec3> c;
        std::vector<Mat3> rotation;
    };

    // Buffers of the step, sized once and reused, so a step allocates nothing after the
    // first (the Hessian pattern only grows when a contact couples a node to a new body).
    struct Workspace {
        BlockPattern pattern;
        ElementBlockSlots tet_slots;
        std::vector<double> hessian;          // 9 values per pattern block
        std::vector<double> tissue_hessian;   // the tissue part of `hessian`
        std::vector<double> damping_hessian;  // tissue part at the prediction (Rayleigh)
        std::vector<double> system;           // (1 + h alpha) M + h^2 H + h gamma H_tissue
        std::vector<std::pair<int, int>> missing;
        std::vector<char> free_mask;
        std::vector<Mat3> body_inertia;  // world frame
        Eigen::VectorXd gradient, velocity, rhs, delta, first_delta, v_plus, iterate;
        Eigen::VectorXd mass_velocity, mass_trial, tissue_trial;
        Configuration start, predicted, trial;
        BlockJacobiPreconditioner preconditioner;
        PcgWorkspace pcg;
        SparseDirectSolver direct;
        // The helper thread's: the cold solve, and a line-search point with its buffers.
        Eigen::VectorXd cold_delta;
        PcgWorkspace cold_pcg;
        Eigen::VectorXd ahead_v, ahead_mass, ahead_tissue;
        Configuration ahead_trial;
    };

  private:
    // energy_reference: the energy guard's reference when the caller has it (NaN: measure).
    bool advance(double dt_s, int depth, StepReport& report,
                 double energy_reference = std::numeric_limits<double>::quiet_NaN());
    // The Newton system at v+ = iterate, its right-hand side and preconditioner.
    // (w.mass_velocity = M v must be set.)
    void buildSystem(const Eigen::VectorXd& iterate, double h, Workspace& w);
    void detectContacts(const Configuration& q);
    void updateAnchors();
    [[nodiscard]] std::size_t anchorSlot(int node, int collider) const {
        return static_cast<std::size_t>(collider) * x_.size() + static_cast<std::size_t>(node);
    }
    [[nodiscard]] Configuration currentConfiguration() const;
    void currentConfiguration(Configuration& out) const;
    // Kinetic energy of the nodes and the dynamic bodies at the current velocities.
    [[nodiscard]] double kineticEnergy() const noexcept;
    [[nodiscard]] double energyNow();
    // Potential of the current state q (= x_ and the bodies), with the tissue term cached.
    [[nodiscard]] double potentialNow(const Configuration& q);
    [[nodiscard]] std::pair<Vec3, Mat3> colliderPose(const Configuration& q, int collider) const;

    SolverSettings settings_;
    std::vector<Vec3> rest_;
    std::vector<Vec3> x_;
    std::vector<Vec3> v_;
    std::vector<double> node_mass_;
    std::vector<Vec3> node_force_;
    std::vector<std::array<bool, 3>> pinned_;
    std::vector<int> skin_;
    std::vector<Tet> tets_;
    std::vector<Body> bodies_;
    std::vector<Joint> joints_;
    std::vector<Attachment> attachments_;
    std::vector<Collider> colliders_;
    std::vector<Contact> contacts_;
    // Friction anchors by collider * nodeCount() + node; only pairs in contact are valid.
    std::vector<Anchor> anchors_;
    std::vector<char> anchor_valid_;
    std::size_t anchor_node_count_{0};  // node count the anchor slots were laid out for
    std::vector<ContactForce> contact_forces_;
    Eigen::VectorXd warm_start_;
    StepReport pending_;  // input rejections and clamps waiting for the next report
    // Tissue energy of x_ (it depends on node positions only), while they are unchanged.
    double tissue_energy_{0.0};
    bool tissue_energy_valid_{false};
    Workspace work_;
    // Made by the first step that uses it (settings_.use_helper_thread).
    std::unique_ptr<HelperThread> helper_;

    friend struct EnergyTerms;
};

}  // namespace haptic::softhand
