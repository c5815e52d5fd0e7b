#include "haptic/kinesthetic/kmetric_projection.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>

namespace haptic::kinesthetic {
namespace {

// Independent reference: enumerate every active subset of size <= n, solve its equality QP and
// keep the one that satisfies all KKT conditions (primal feasible, multipliers >= 0).
ConfigVector bruteForceProjection(const Eigen::MatrixXd& K, const Eigen::VectorXd& y0,
                                  const Eigen::MatrixXd& C, const Eigen::VectorXd& d) {
    const int n = static_cast<int>(y0.size());
    const int count = static_cast<int>(C.cols());
    double best = std::numeric_limits<double>::infinity();
    Eigen::VectorXd best_y = y0;
    for (int mask = 0; mask < (1 << count); ++mask) {
        std::vector<int> set;
        for (int j = 0; j < count; ++j) {
            if (mask & (1 << j)) {
                set.push_back(j);
            }
        }
        if (static_cast<int>(set.size()) > n) {
            continue;
        }
        if (set.empty()) {
            if (((C.transpose() * y0 - d).array() >= -1e-9).all()) {
                return y0;  // already feasible: zero cost, nothing can beat it
            }
            continue;
        }
        Eigen::MatrixXd Cs(n, set.size());
        Eigen::VectorXd ds(set.size());
        for (std::size_t i = 0; i < set.size(); ++i) {
            Cs.col(static_cast<Eigen::Index>(i)) = C.col(set[i]);
            ds[static_cast<Eigen::Index>(i)] = d[set[i]];
        }
        const Eigen::MatrixXd Kinv_C = K.ldlt().solve(Cs);
        const Eigen::MatrixXd Q = Cs.transpose() * Kinv_C;
        if (set.size() > 0 && Q.fullPivLu().rank() < static_cast<int>(set.size())) {
            continue;
        }
        const Eigen::VectorXd lambda =
            set.empty() ? Eigen::VectorXd()
                        : Eigen::VectorXd(Q.ldlt().solve(ds - Cs.transpose() * y0));
        const Eigen::VectorXd y = set.empty() ? y0 : Eigen::VectorXd(y0 + Kinv_C * lambda);
        if (set.size() > 0 && lambda.minCoeff() < -1e-12) {
            continue;
        }
        if (((C.transpose() * y - d).array() < -1e-9).any()) {
            continue;
        }
        const double cost = (y - y0).dot(K * (y - y0));
        if (cost < best) {
            best = cost;
            best_y = y;
        }
    }
    return best_y;
}

TEST(KMetricProjector, SinglePlaneMatchesTheClosedForm) {
    // §6.5: x_p = x + delta K^-1 n / (n^T K^-1 n).
    ConfigMatrix K(2, 2);
    K << 1000, 200, 200, 300;
    ConfigVector x(2);
    x << 0.1, -0.02;
    ConstraintMatrix C(2, 1);
    C << 0.0, 1.0;
    ConstraintVector d = ConstraintVector::Zero(1);
    KMetricProjector sut;
    ConfigVector y;
    const auto result = sut.project(K, x, C, d, ActiveSet{}, y);
    ASSERT_EQ(result.status, SolveStatus::kOptimal);
    const Eigen::Vector2d n(0.0, 1.0);
    const Eigen::Vector2d Kinv_n = Eigen::Matrix2d(K).inverse() * n;
    const Eigen::Vector2d expected = Eigen::Vector2d(x) + 0.02 * Kinv_n / n.dot(Kinv_n);
    EXPECT_NEAR(y[0], expected[0], 1e-14);
    EXPECT_NEAR(y[1], expected[1], 1e-14);
    EXPECT_EQ(result.active.size, 1);
}

TEST(KMetricProjector, MatchesBruteForceOnRandomCornersAndWarmStartsInOneIteration) {
    std::mt19937 rng(7);
    std::normal_distribution<double> gauss;
    KMetricProjector sut;
    int checked = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const int n = 2 + trial % 2;
        const int count = 1 + trial % 6;
        Eigen::MatrixXd L = Eigen::MatrixXd::Random(n, n);
        Eigen::MatrixXd K = L * L.transpose() + 0.2 * Eigen::MatrixXd::Identity(n, n);
        Eigen::MatrixXd C(n, count);
        Eigen::VectorXd feasible_point(n);
        for (int i = 0; i < n; ++i) {
            feasible_point[i] = gauss(rng);
        }
        Eigen::VectorXd d(count);
        for (int j = 0; j < count; ++j) {
            for (int i = 0; i < n; ++i) {
                C(i, j) = gauss(rng);
            }
            d[j] = C.col(j).dot(feasible_point) - std::abs(gauss(rng));
        }
        Eigen::VectorXd y0(n);
        for (int i = 0; i < n; ++i) {
            y0[i] = feasible_point[i] + 3.0 * gauss(rng);
        }
        ConfigVector y;
        const auto result = sut.project(ConfigMatrix(K), ConfigVector(y0), ConstraintMatrix(C),
                                        ConstraintVector(d), ActiveSet{}, y);
        ASSERT_EQ(result.status, SolveStatus::kOptimal) << "trial " << trial;
        const Eigen::VectorXd expected = bruteForceProjection(K, y0, C, d);
        EXPECT_LT((Eigen::VectorXd(y) - expected).norm(), 1e-8 * (1 + expected.norm()))
            << "trial " << trial;
        EXPECT_LT(result.max_violation, 1e-9);

        ConfigVector y_again;
        const auto warm = sut.project(ConfigMatrix(K), ConfigVector(y0), ConstraintMatrix(C),
                                      ConstraintVector(d), result.active, y_again);
        EXPECT_EQ(warm.iterations, 1) << "trial " << trial;
        EXPECT_LT((y_again - y).norm(), 1e-10);
        ++checked;
    }
    EXPECT_EQ(checked, 300);
}

struct Problem {
    ConfigMatrix K = ConfigMatrix::Identity(2, 2) * 1000.0;
    ConfigVector y0 = ConfigVector::Zero(2);
    ConstraintMatrix C;
    ConstraintVector d;
};

Problem corner() {
    // Three planes through a 2-D corner, the origin violating all of them.
    Problem p;
    p.C.resize(2, 3);
    p.C << 1, 0, 1, 0, 1, 1;
    p.d.resize(3);
    p.d << 0.01, 0.01, 0.03;
    return p;
}

TEST(KMetricProjector, ParallelDuplicatesAreHarmless) {
    Problem p;
    p.C.resize(2, 3);
    p.C << 0, 0, 0, 1, 1, 2;
    p.d.resize(3);
    p.d << 0.01, 0.01, 0.02;
    ConfigVector y;
    const auto result = KMetricProjector().project(p.K, p.y0, p.C, p.d, ActiveSet{}, y);
    EXPECT_EQ(result.status, SolveStatus::kOptimal);
    EXPECT_NEAR(y[1], 0.01, 1e-14);
    EXPECT_EQ(result.active.size, 1);
}

TEST(KMetricProjector, ContradictoryParallelPlanesAreReportedInfeasible) {
    Problem p;
    p.C.resize(2, 2);
    p.C << 0, 0, 1, -1;
    p.d.resize(2);
    p.d << 0.02, 0.0;  // y >= 0.02 and y <= 0
    ConfigVector y;
    const auto result = KMetricProjector().project(p.K, p.y0, p.C, p.d, ActiveSet{}, y);
    EXPECT_EQ(result.status, SolveStatus::kInfeasible);
    EXPECT_TRUE(y.allFinite());
}

TEST(KMetricProjector, ZeroNormalWithPositiveOffsetIsInfeasible) {
    Problem p;
    p.C = ConstraintMatrix::Zero(2, 1);
    p.d = ConstraintVector::Constant(1, 0.01);
    ConfigVector y;
    const auto result = KMetricProjector().project(p.K, p.y0, p.C, p.d, ActiveSet{}, y);
    EXPECT_EQ(result.status, SolveStatus::kInfeasible);
    EXPECT_TRUE(y.allFinite());
}

TEST(KMetricProjector, IterationBoundIsReportedWithAFiniteIterate) {
    const Problem p = corner();
    ConfigVector y;
    const auto result = KMetricProjector(1).project(p.K, p.y0, p.C, p.d, ActiveSet{}, y);
    EXPECT_EQ(result.status, SolveStatus::kIterationLimit);
    EXPECT_EQ(result.iterations, 1);
    EXPECT_TRUE(y.allFinite());
    EXPECT_GT(result.max_violation, 0.0);

    const auto full = KMetricProjector(16).project(p.K, p.y0, p.C, p.d, ActiveSet{}, y);
    EXPECT_EQ(full.status, SolveStatus::kOptimal);
    EXPECT_NEAR(y[0] + y[1], 0.03, 1e-12);
}

TEST(KMetricProjector, RejectsZeroStiffnessAndNaN) {
    Problem p = corner();
    ConfigVector y;
    p.K.setZero();
    EXPECT_EQ(KMetricProjector().project(p.K, p.y0, p.C, p.d, ActiveSet{}, y).status,
              SolveStatus::kInvalidInput);
    EXPECT_EQ(y, p.y0);
    p = corner();
    p.y0[0] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(KMetricProjector().project(p.K, p.y0, p.C, p.d, ActiveSet{}, y).status,
              SolveStatus::kInvalidInput);
    p = corner();
    p.d[1] = std::numeric_limits<double>::infinity();
    EXPECT_EQ(KMetricProjector().project(p.K, p.y0, p.C, p.d, ActiveSet{}, y).status,
              SolveStatus::kInvalidInput);
}

TEST(KMetricProjector, HugeAndAnisotropicStiffnessStillProjects) {
    Problem p = corner();
    p.K << 1e9, 0, 0, 1e-3;  // condition number 1e12
    ConfigVector y;
    const auto result = KMetricProjector().project(p.K, p.y0, p.C, p.d, ActiveSet{}, y);
    EXPECT_NE(result.status, SolveStatus::kInvalidInput);
    EXPECT_TRUE(y.allFinite());
    EXPECT_LT(result.max_violation, 1e-9);
}

}  // namespace
}  // namespace haptic::kinesthetic
