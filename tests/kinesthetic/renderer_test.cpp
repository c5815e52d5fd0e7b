#include "haptic/kinesthetic/renderer.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "contact_rows.hpp"
#include "haptic/config/device.hpp"
#include "haptic/kinesthetic/anisotropic.hpp"
#include "haptic/kinesthetic/study.hpp"

namespace haptic::kinesthetic {
namespace {

using study::WallCase;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr RenderingMethod kAllMethods[] = {
    RenderingMethod::kStandard,           RenderingMethod::kNaive,
    RenderingMethod::kNullspace,          RenderingMethod::kSubspace,
    RenderingMethod::kLinearizedSubspace, RenderingMethod::kAnisotropic};

// Done when: at rho* the equilibrium force equals P_a F_full to 1e-9 relative, for at least 5
// wall angles and 3 stiffness ratios. Both equilibria are solved numerically through the
// renderer (fully actuated device with `standard` vs underactuated with `anisotropic`).
TEST(AnisotropicRendering, BestMatchAtRhoStarForEveryWallAngleAndStiffnessRatio) {
    for (const double ratio : {0.3, 1.0, 3.3}) {
        for (const double beta_deg : {0.0, 15.0, 30.0, 45.0, 60.0, 75.0}) {
            WallCase wall;
            wall.beta_rad = beta_deg * kDeg;
            wall.k_u = 300.0;
            wall.k_a = ratio * wall.k_u;
            const auto m =
                study::measureWall(wall, RenderingMethod::kAnisotropic, RhoMode::kClosedForm, 0.0);
            ASSERT_TRUE(m.converged);
            EXPECT_NEAR(m.rho, wall.k_u / (wall.k_u + wall.k_a), 1e-15);
            EXPECT_LE(m.ghost_force, 1e-9 * m.full_force)
                << "beta " << beta_deg << " k_a/k_u " << ratio;
            // Unavoidable residual |F_full| sin(beta) (§6.6).
            EXPECT_NEAR(m.force_error, m.full_force * std::sin(wall.beta_rad), 1e-9 * m.full_force);
        }
    }
}

// Done when: naive and subspace rendering show the ghost force the closed forms predict.
TEST(GhostForces, NaiveAndSubspaceMatchTheClosedForms) {
    for (const double ratio : {0.5, 3.3, 10.0}) {
        for (const double beta_deg : {10.0, 30.0, 50.0, 70.0}) {
            WallCase wall;
            wall.beta_rad = beta_deg * kDeg;
            wall.k_a = ratio * wall.k_u;
            const double c = std::cos(wall.beta_rad);
            const auto naive_prediction =
                predictSingleWall(wall.k_a, wall.k_u, wall.depth_u_m, c, 1.0);
            const auto subspace_prediction = predictSingleWall(
                wall.k_a, wall.k_u, wall.depth_u_m, c, std::numeric_limits<double>::infinity());
            // §6.6: |g(1)| = |F_full| c ((k_u + k_a)/(k_u + k_a c^2) - 1), |g(inf)| = |F_full| (1/c
            // - c).
            const double full = naive_prediction.full_force;
            EXPECT_NEAR(naive_prediction.ghost_force,
                        full * c * ((wall.k_u + wall.k_a) / (wall.k_u + wall.k_a * c * c) - 1.0),
                        1e-12);
            EXPECT_NEAR(subspace_prediction.ghost_force, full * (1.0 / c - c), 1e-12);

            const auto naive =
                study::measureWall(wall, RenderingMethod::kNaive, RhoMode::kManual, 1);
            EXPECT_NEAR(naive.ghost_force, naive_prediction.ghost_force, 1e-9 * full);
            EXPECT_NEAR(naive.tangential_force, naive_prediction.tangential_force, 1e-9 * full);
            for (const auto method :
                 {RenderingMethod::kSubspace, RenderingMethod::kLinearizedSubspace}) {
                const auto sub = study::measureWall(wall, method, RhoMode::kManual, 1);
                ASSERT_TRUE(sub.converged);
                EXPECT_NEAR(sub.ghost_force, subspace_prediction.ghost_force, 1e-9 * full);
                EXPECT_NEAR(sub.normal_force, full, 1e-9 * full);  // normal force kept exactly
            }
        }
    }
}

TEST(GhostForces, ReproduceTheWorkedNumbersOfAlgorithmsSection66) {
    WallCase wall;  // k_a = 1000, k_u = 300, 10 mm deep
    struct Row {
        double beta_deg;
        RenderingMethod method;
        double force, normal, tangential, error;
    };
    const Row rows[] = {
        {30, RenderingMethod::kSubspace, 2.665, 2.308, 1.332, 1.332},
        {30, RenderingMethod::kNaive, 2.474, 2.143, 1.237, 1.248},
        {30, RenderingMethod::kAnisotropic, 1.999, 1.731, 0.999, 1.154},
        {60, RenderingMethod::kSubspace, 4.615, 2.308, 3.997, 3.997},
        {60, RenderingMethod::kNaive, 2.727, 1.364, 2.362, 2.544},
        {60, RenderingMethod::kAnisotropic, 1.154, 0.577, 0.999, 1.999},
    };
    for (const Row& row : rows) {
        wall.beta_rad = row.beta_deg * kDeg;
        const auto m = study::measureWall(wall, row.method, RhoMode::kClosedForm, 0);
        EXPECT_NEAR(m.full_force, 2.308, 1e-3);
        EXPECT_NEAR(m.rendered_force, row.force, 1.5e-3) << row.beta_deg;
        EXPECT_NEAR(m.normal_force, row.normal, 1.5e-3) << row.beta_deg;
        EXPECT_NEAR(m.tangential_force, row.tangential, 1.5e-3) << row.beta_deg;
        EXPECT_NEAR(m.force_error, row.error, 1.5e-3) << row.beta_deg;
    }
}

ConfigMatrix projectorOn(const Eigen::Vector2d& a) {
    return ConfigMatrix(a * a.transpose() / a.squaredNorm());
}

// Done when: for a single constraint, rho* is the argmin of the numeric search.
TEST(RhoSearch, SingleConstraintArgminIsTheClosedForm) {
    for (const double ratio : {0.1, 1.0, 3.3, 30.0}) {
        for (const double beta_deg : {5.0, 30.0, 60.0, 85.0}) {
            const double k_u = 300.0;
            const double k_a = ratio * k_u;
            const Eigen::Vector2d a = study::actuatedDirection(beta_deg * kDeg).col(0);
            const ConfigMatrix K_u = ConfigMatrix::Identity(2, 2) * k_u;
            ConfigVector normal(2);
            normal << 0.0, 2.0;  // any length
            const auto search = searchOptimalRho(projectorOn(a), k_a, K_u, normal);
            ASSERT_TRUE(search.valid);
            EXPECT_NEAR(std::log(search.rho), std::log(optimalRhoIsotropic(k_a, k_u)), 1e-6);
            EXPECT_LT(search.mismatch, 1e-6 * k_a);
        }
    }
}

TEST(RhoSearch, DegenerateInputFallsBackToNaiveWithAReport) {
    const Eigen::Vector2d a = study::actuatedDirection(30 * kDeg).col(0);
    const ConfigMatrix K_u = ConfigMatrix::Identity(2, 2) * 300.0;
    ConfigVector normal(2);
    normal << 0.0, std::numeric_limits<double>::quiet_NaN();
    auto search = searchOptimalRho(projectorOn(a), 1000.0, K_u, normal);
    EXPECT_FALSE(search.valid);
    EXPECT_EQ(search.rho, 1.0);
    normal << 0.0, 0.0;  // zero normal
    EXPECT_FALSE(searchOptimalRho(projectorOn(a), 1000.0, K_u, normal).valid);
    normal << 0.0, 1.0;
    EXPECT_FALSE(searchOptimalRho(projectorOn(a), 0.0, K_u, normal).valid);  // zero k_a
    EXPECT_FALSE(searchOptimalRho(projectorOn(a), 1000.0, ConfigMatrix::Zero(2, 2), normal).valid);
    EXPECT_TRUE(std::isnan(optimalRhoIsotropic(0.0, 300.0)));
    // Huge stiffness: bounded search still lands on the closed form.
    search = searchOptimalRho(projectorOn(a), 1e9, K_u, normal);
    ASSERT_TRUE(search.valid);
    EXPECT_NEAR(std::log(search.rho), std::log(optimalRhoIsotropic(1e9, 300.0)), 1e-5);
    EXPECT_EQ(search.evaluations, 2 + 48);
}

TEST(RhoSearch, AnisotropicUserStiffnessMinimisesTheNumericEquilibriumMismatch) {
    // Stiffer across the wall than along it, and coupled: no §6.6 closed form applies.
    ConfigMatrix K_u(2, 2);
    K_u << 200.0, 80.0, 80.0, 600.0;
    WallCase wall;
    wall.beta_rad = 40.0 * kDeg;
    const Eigen::Vector2d a = study::actuatedDirection(wall.beta_rad).col(0);
    ConfigVector normal(2);
    normal << 0.0, 1.0;
    const auto search = searchOptimalRho(projectorOn(a), wall.k_a, K_u, normal);
    ASSERT_TRUE(search.valid);
    // Our generalised closed form (*) in anisotropic.hpp agrees...
    EXPECT_NEAR(search.rho, optimalRhoAnisotropicUser(projectorOn(a), wall.k_a, K_u, normal),
                1e-6 * search.rho);

    // ...and an independent check: Newton equilibria of the real renderer over a rho grid.
    auto measure = [&](double rho) {
        ConstraintMatrix C;
        ConstraintVector d;
        study::wallConstraint(2, C, d);
        const Eigen::Vector2d x_u(0.05, -wall.depth_u_m);
        const LinearPointDevice full_device(Eigen::MatrixXd::Identity(2, 2), 1e6);
        RenderParameters p;
        p.method = RenderingMethod::kStandard;
        p.tracking_stiffness = wall.k_a;
        KinestheticRenderer full(full_device, p);
        const auto reference = study::solveEquilibrium(full, Eigen::MatrixXd(K_u), x_u, C, d);
        const LinearPointDevice device(study::actuatedDirection(wall.beta_rad), 1e6);
        p.method = RenderingMethod::kAnisotropic;
        p.rho_mode = RhoMode::kManual;
        p.rho_override = rho;
        KinestheticRenderer sut(device, p);
        const auto eq = study::solveEquilibrium(sut, Eigen::MatrixXd(K_u), x_u, C, d);
        const Eigen::Vector2d F_full = reference.rendered_force;
        return (Eigen::Vector2d(eq.rendered_force) - a * a.dot(F_full)).norm();
    };
    const double at_search = measure(search.rho);
    EXPECT_LT(at_search, 1e-9);
    for (double log_rho = -4.0; log_rho <= 2.0; log_rho += 0.25) {
        EXPECT_LE(at_search, measure(std::pow(10.0, log_rho)) + 1e-12);
    }
}

TEST(KinestheticRenderer, RhoModesAndRunTimeMethodSwitch) {
    const LinearPointDevice device(study::actuatedDirection(30 * kDeg), 100.0);
    RenderParameters p;
    p.rho_mode = RhoMode::kManual;
    p.rho_override = 0.05;
    KinestheticRenderer sut(device, p);
    ConstraintMatrix C;
    ConstraintVector d;
    study::wallConstraint(2, C, d);
    ConfigVector q(2);
    q << 0.0, -0.01;
    const ConfigVector zero = ConfigVector::Zero(2);
    RenderOutput out;
    sut.tick(q, zero, C, d, out);
    EXPECT_DOUBLE_EQ(out.rho, 0.05);
    EXPECT_EQ(out.fault, RenderFault::kNone);
    const double anisotropic_force = out.actuator_force[0];

    p.rho_mode = RhoMode::kNumericSearch;
    ASSERT_EQ(sut.setParameters(p), nullptr);
    sut.tick(q, zero, C, d, out);
    EXPECT_NEAR(out.rho, optimalRhoIsotropic(p.tracking_stiffness, p.user_stiffness), 1e-6);

    sut.setMethod(RenderingMethod::kSubspace);
    sut.tick(q, zero, C, d, out);
    EXPECT_GT(out.actuator_force[0], anisotropic_force);
    EXPECT_NEAR(out.proxy[1], 0.0, 1e-12);  // proxy on the wall, moved along a only
}

config::ExoskeletonConfig shippedExoskeleton() {
    return config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/exoskeleton.yaml")
        .exoskeleton();
}

using testing::phalanxContact;

class NullspaceRendering : public ::testing::Test {
  protected:
    RenderOutput render(RenderingMethod method, std::span<const msgs::LinearConstraint> rows) {
        RenderParameters p;
        p.method = method;
        p.tracking_stiffness = 2.0;  // N m / rad, the shipped k_a
        KinestheticRenderer renderer(exo_, p);
        RenderOutput out;
        renderer.tick(q_, ConfigVector::Zero(3), rows, out);
        return out;
    }
    // The part of a joint torque the one actuator cannot render.
    double unrenderable(const ConfigVector& tau) const {
        ActuationMatrix B;
        exo_.actuationMatrix(q_, B);
        const ConfigVector b = B.col(0);
        return (tau - b * (b.dot(tau) / b.squaredNorm())).norm();
    }
    double checkBestSplit(double middle_depth_m, double tip_depth_m);
    const config::ExoskeletonConfig config_ = shippedExoskeleton();
    const ExoskeletonDevice exo_{config_};
    const ConfigVector q_ = (ConfigVector(3) << 0.5, 0.7, 0.4).finished();
    static constexpr double kNormalAngle = 2.6;  // the surface the finger presses on
};

// §5.3 of the design notes: with a single point contact there is no freedom left, and the
// method is naive.
TEST_F(NullspaceRendering, IsNaiveForASingleContact) {
    const msgs::LinearConstraint tip = phalanxContact(config_, q_, 2, 1.0, 0.003, kNormalAngle);
    const RenderOutput naive = render(RenderingMethod::kNaive, {&tip, 1});
    const RenderOutput out = render(RenderingMethod::kNullspace, {&tip, 1});
    ASSERT_TRUE(out.in_contact);
    EXPECT_EQ(out.coupling_force, naive.coupling_force);
    EXPECT_EQ(out.actuator_force, naive.actuator_force);
}

// Two contacts whose normals differ fix both forces by their resultant: naive again.
TEST_F(NullspaceRendering, IsNaiveWhenTheResultantFixesEveryContactForce) {
    const std::array<msgs::LinearConstraint, 2> rows{
        phalanxContact(config_, q_, 1, 0.6, 0.0025, kNormalAngle),
        phalanxContact(config_, q_, 2, 1.0, 0.003, kNormalAngle + 0.8)};  // both active
    const RenderOutput naive = render(RenderingMethod::kNaive, rows);
    ASSERT_EQ(naive.active_constraints, 2);
    const RenderOutput out = render(RenderingMethod::kNullspace, rows);
    EXPECT_EQ(out.coupling_force, naive.coupling_force);
}

// The middle phalanx and the fingertip on one flat face: the same resultant and total can be
// split between them in a one-parameter family, mu_naive + t (1, -1), with |t| <= min(mu_naive)
// (no contact's force changes by more than itself). Checks the method's split against the best
// of that family by brute force and returns the brute force's t. (The two rows are nearly
// parallel, so both are active at the naive proxy only for depth ratios of about 0.58-0.63.)
double NullspaceRendering::checkBestSplit(double middle_depth_m, double tip_depth_m) {
    const std::array<msgs::LinearConstraint, 2> rows{
        phalanxContact(config_, q_, 1, 0.6, middle_depth_m, kNormalAngle),
        phalanxContact(config_, q_, 2, 1.0, tip_depth_m, kNormalAngle)};
    const RenderOutput naive = render(RenderingMethod::kNaive, rows);
    EXPECT_EQ(naive.active_constraints, 2);
    const RenderOutput out = render(RenderingMethod::kNullspace, rows);
    EXPECT_TRUE(out.in_contact);
    Eigen::Matrix<double, 3, 2> A;
    for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 3; ++i) {
            A(i, j) = rows[static_cast<std::size_t>(j)].a[static_cast<std::size_t>(i)];
        }
    }
    const auto forces = [&](const ConfigVector& tau) -> Eigen::Vector2d {
        return (A.transpose() * A).ldlt().solve(A.transpose() * Eigen::Vector3d(tau));
    };
    const Eigen::Vector2d mu_naive = forces(naive.coupling_force);
    const Eigen::Vector2d mu = forces(out.coupling_force);
    // The torque stays a combination of the two contacts' rows, with the same resultant.
    EXPECT_LT((A * mu - Eigen::Vector3d(out.coupling_force)).norm(),
              1e-12 * naive.coupling_force.norm());
    EXPECT_NEAR(mu.sum(), mu_naive.sum(), 1e-9 * mu_naive.sum());
    const double bound = mu_naive.minCoeff();
    EXPECT_GT(bound, 0.0);
    EXPECT_LE((mu - mu_naive).cwiseAbs().maxCoeff(), bound * (1.0 + 1e-9));
    double best = std::numeric_limits<double>::infinity();
    double best_t = 0.0;
    const int steps = 200000;
    for (int i = 0; i <= steps; ++i) {
        const double t = bound * (2.0 * i / steps - 1.0);
        const Eigen::Vector3d tau = A * (mu_naive + Eigen::Vector2d(t, -t));
        const double value = unrenderable(ConfigVector(tau));
        if (value < best) {
            best = value;
            best_t = t;
        }
    }
    EXPECT_LT(unrenderable(out.coupling_force), unrenderable(naive.coupling_force));
    EXPECT_NEAR(unrenderable(out.coupling_force), best, 1e-6 * unrenderable(naive.coupling_force));
    EXPECT_NE(out.actuator_force[0], naive.actuator_force[0]);
    return best_t / bound;
}

TEST_F(NullspaceRendering, SplitsForcesOnOneFaceAsTheActuatorRendersBest) {
    const double t = checkBestSplit(0.0018, 0.003);
    EXPECT_LT(std::abs(t), 0.99) << "the best split lies inside the bounds";
}

TEST_F(NullspaceRendering, StopsAtTheBoundWhereTheBestSplitLiesBeyondIt) {
    // Deeper in the middle: the fingertip carries little, and moving more than that is barred.
    const double t = checkBestSplit(0.00188, 0.003);
    EXPECT_GT(std::abs(t), 0.999) << "the best split lies on the bound";
}

// Contacts pushing from opposite sides: moving force between them keeping the resultant would
// squeeze the finger harder; the total is kept too, so nothing moves.
TEST_F(NullspaceRendering, IsNaiveForOpposedContacts) {
    const std::array<msgs::LinearConstraint, 2> rows{
        phalanxContact(config_, q_, 1, 0.6, 0.002, kNormalAngle),
        phalanxContact(config_, q_, 2, 1.0, 0.002, kNormalAngle - std::numbers::pi)};
    const RenderOutput naive = render(RenderingMethod::kNaive, rows);
    ASSERT_EQ(naive.active_constraints, 2);
    const RenderOutput out = render(RenderingMethod::kNullspace, rows);
    EXPECT_EQ(out.coupling_force, naive.coupling_force);
}

// A second contact becoming active moves nothing at first: the force is continuous through
// the onset (a step would stay as the sweep gets finer; a continuous change shrinks with it).
TEST_F(NullspaceRendering, HasNoStepWhereASecondContactBecomesActive) {
    const msgs::LinearConstraint tip = phalanxContact(config_, q_, 2, 1.0, 0.003, kNormalAngle);
    const auto largestChange = [&](int samples) {
        double largest = 0.0;
        double last = 0.0;
        int onsets = 0;
        int last_active = 0;
        for (int i = 0; i <= samples; ++i) {
            const double ratio = 0.575 + 0.015 * i / samples;  // through the onset near 0.583
            const std::array<msgs::LinearConstraint, 2> rows{
                phalanxContact(config_, q_, 1, 0.6, ratio * 0.003, kNormalAngle), tip};
            const RenderOutput out = render(RenderingMethod::kNullspace, rows);
            if (i > 0) {
                largest = std::max(largest, std::abs(out.actuator_force[0] - last));
            }
            onsets += out.active_constraints == 2 && last_active == 1 ? 1 : 0;
            last_active = out.active_constraints;
            last = out.actuator_force[0];
        }
        EXPECT_EQ(onsets, 1);
        return largest;
    };
    const double coarse = largestChange(300);
    const double fine = largestChange(3000);
    EXPECT_GT(coarse, 0.0);
    EXPECT_LT(fine, 0.2 * coarse) << "a step at the onset: " << fine << " N";
}

// The largest change of the actuator force between neighbouring samples of a sweep, at two
// resolutions: a step stays as the sweep gets finer, a continuous change shrinks with it.
template <typename RowsAt>
std::pair<double, double> largestChanges(
    const RowsAt& rows_at,
    const std::function<RenderOutput(std::span<const msgs::LinearConstraint>)>& render) {
    const auto largest = [&](int samples) {
        double worst = 0.0;
        double last = 0.0;
        for (int i = 0; i <= samples; ++i) {
            const auto rows = rows_at(static_cast<double>(i) / samples);
            const double u = render(rows).actuator_force[0];
            if (i > 0) {
                worst = std::max(worst, std::abs(u - last));
            }
            last = u;
        }
        return worst;
    };
    return {largest(300), largest(3000)};
}

// The second contact's normal turning away from the first (a contact reaching an edge): the
// redistribution fades out instead of stopping in one tick.
TEST_F(NullspaceRendering, FadesOutContinuouslyAsTheNormalsTurnApart) {
    const auto rows_at = [&](double x) {
        return std::array<msgs::LinearConstraint, 2>{
            phalanxContact(config_, q_, 1, 0.6, 0.0018, kNormalAngle),
            phalanxContact(config_, q_, 2, 1.0, 0.003, kNormalAngle + 0.06 * x)};
    };
    const auto nullspace = [&](std::span<const msgs::LinearConstraint> rows) {
        return render(RenderingMethod::kNullspace, rows);
    };
    const auto start = rows_at(0.0);
    const auto end = rows_at(1.0);
    ASSERT_NE(nullspace(start).coupling_force,
              render(RenderingMethod::kNaive, start).coupling_force);
    EXPECT_EQ(nullspace(end).coupling_force, render(RenderingMethod::kNaive, end).coupling_force)
        << "3.4 degrees apart the normals fix both forces";
    const auto [coarse, fine] = largestChanges(rows_at, nullspace);
    EXPECT_GT(coarse, 0.0);
    EXPECT_LT(fine, 0.2 * coarse) << "a step as the normals turn apart: " << fine << " N";
}

// Rows without their contacts (a sim that does not fill them) say nothing about where each
// force acts: naive, even where the same rows with contacts are redistributed.
TEST_F(NullspaceRendering, IsNaiveForRowsWithoutContacts) {
    std::array<msgs::LinearConstraint, 2> rows{
        phalanxContact(config_, q_, 1, 0.6, 0.0018, kNormalAngle),
        phalanxContact(config_, q_, 2, 1.0, 0.003, kNormalAngle)};
    ASSERT_NE(render(RenderingMethod::kNullspace, rows).coupling_force,
              render(RenderingMethod::kNaive, rows).coupling_force);
    for (auto& row : rows) {
        row.contact = msgs::ContactKinematics{};
    }
    const RenderOutput naive = render(RenderingMethod::kNaive, rows);
    ASSERT_EQ(naive.active_constraints, 2);
    EXPECT_EQ(render(RenderingMethod::kNullspace, rows).coupling_force, naive.coupling_force);
}

// Done when: every solver hits its bound gracefully on degenerate input.
class DegenerateInput : public ::testing::TestWithParam<RenderingMethod> {
  protected:
    const LinearPointDevice device_{study::actuatedDirection(30 * kDeg), 50.0};
    RenderParameters parameters() const {
        RenderParameters p;
        p.method = GetParam();
        return p;
    }
    const ConfigVector zero_ = ConfigVector::Zero(2);
    ConfigVector inside() const {
        ConfigVector q(2);
        q << 0.0, -0.01;
        return q;
    }
    static void expectSafe(const RenderOutput& out) {
        EXPECT_TRUE(out.actuator_force.allFinite());
        EXPECT_TRUE(out.rendered_force.allFinite());
        EXPECT_TRUE(out.proxy.allFinite());
    }
};

TEST_P(DegenerateInput, NaNStateOrConstraintGivesZeroForceAndAReason) {
    KinestheticRenderer sut(device_, parameters());
    ConstraintMatrix C;
    ConstraintVector d;
    study::wallConstraint(2, C, d);
    RenderOutput out;
    ConfigVector q = inside();
    q[0] = std::numeric_limits<double>::quiet_NaN();
    sut.tick(q, zero_, C, d, out);
    EXPECT_EQ(out.fault, RenderFault::kNonFiniteState);
    EXPECT_EQ(out.actuator_force[0], 0.0);
    expectSafe(out);
    C(0, 0) = std::numeric_limits<double>::infinity();
    sut.tick(inside(), zero_, C, d, out);
    EXPECT_EQ(out.fault, RenderFault::kInvalidConstraints);
    EXPECT_EQ(out.actuator_force[0], 0.0);
    EXPECT_STRNE(toString(out.fault), "unknown");
}

TEST_P(DegenerateInput, ParallelContradictoryConstraintsAreFlaggedNotCrashed) {
    KinestheticRenderer sut(device_, parameters());
    ConstraintMatrix C(2, 3);
    C << 0, 0, 0, 1, 1, -1;
    ConstraintVector d(3);
    d << 0.0, 0.0, 0.005;  // y >= 0 twice, and y <= -0.005
    RenderOutput out;
    sut.tick(inside(), zero_, C, d, out);
    expectSafe(out);
    if (GetParam() != RenderingMethod::kLinearizedSubspace) {
        EXPECT_NE(out.fault, RenderFault::kNone) << toString(out.fault);
    }
}

TEST_P(DegenerateInput, NormalInTheNonActuatedSubspace) {
    const LinearPointDevice device(study::actuatedDirection(90 * kDeg), 50.0);  // a = (1, 0)
    KinestheticRenderer sut(device, parameters());
    ConstraintMatrix C;
    ConstraintVector d;
    study::wallConstraint(2, C, d);  // n = (0, 1), c = 0
    RenderOutput out;
    sut.tick(inside(), zero_, C, d, out);
    expectSafe(out);
    EXPECT_NEAR(out.actuator_force[0], 0.0, 1e-12);
    if (GetParam() == RenderingMethod::kSubspace ||
        GetParam() == RenderingMethod::kLinearizedSubspace) {
        EXPECT_EQ(out.fault, RenderFault::kNotRenderable);
    }
}

TEST_P(DegenerateInput, ZeroStiffnessIsRejectedAndHugeStiffnessStaysFinite) {
    RenderParameters p = parameters();
    p.tracking_stiffness = 0.0;
    EXPECT_THROW(KinestheticRenderer(device_, p), std::invalid_argument);
    p.tracking_stiffness = 1000.0;
    KinestheticRenderer sut(device_, p);
    RenderParameters bad = p;
    bad.user_stiffness = std::numeric_limits<double>::quiet_NaN();
    EXPECT_NE(sut.setParameters(bad), nullptr);
    EXPECT_EQ(sut.parameters().user_stiffness, p.user_stiffness);
    p.tracking_stiffness = 1e12;
    ASSERT_EQ(sut.setParameters(p), nullptr);
    ConstraintMatrix C;
    ConstraintVector d;
    study::wallConstraint(2, C, d);
    RenderOutput out;
    sut.tick(inside(), zero_, C, d, out);
    expectSafe(out);
    EXPECT_GT(std::abs(out.actuator_force[0]), 0.0);
}

TEST_P(DegenerateInput, IterationBoundOnTheExoskeletonWithFourConstraints) {
    const ExoskeletonDevice exo(shippedExoskeleton());
    RenderParameters p = parameters();
    p.tracking_stiffness = 2.0;
    p.max_iterations = 1;
    KinestheticRenderer sut(exo, p);
    ConfigVector q(3);
    q << 0.6, 0.9, 0.5;
    ConstraintMatrix C(3, 4);
    C << -1, 0, -0.2, -1, 0, -1, -1, -0.5, -0.3, -0.2, 0, -1;
    ConstraintVector d = -(C.transpose() * q);
    d.array() += 0.02;
    RenderOutput out;
    sut.tick(q, ConfigVector::Zero(3), C, d, out);
    expectSafe(out);
    const auto method = GetParam();
    if (method != RenderingMethod::kLinearizedSubspace) {
        EXPECT_EQ(out.fault, RenderFault::kSolverIterationLimit) << toString(out.fault);
        EXPECT_EQ(out.iterations, 1);
    }
}

// Named after the config spelling, so ctest lists "DegenerateInput.X/naive" and so on.
INSTANTIATE_TEST_SUITE_P(AllMethods, DegenerateInput, ::testing::ValuesIn(kAllMethods),
                         [](const ::testing::TestParamInfo<RenderingMethod>& info) {
                             return std::string(config::toString(info.param));
                         });

}  // namespace
}  // namespace haptic::kinesthetic
