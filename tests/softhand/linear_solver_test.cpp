// The two linear solvers of the Newton step (LinearSolver): the sparse direct factorisation
// against a dense solve, with pinned DoFs and on an indefinite system, PCG against it, and a
// whole fingertip press stepped with each.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <utility>
#include <vector>

#include "haptic/config/scene.hpp"
#include "haptic/softhand/block_sparse.hpp"
#include "haptic/softhand/hand_builder.hpp"
#include "haptic/softhand/pcg.hpp"
#include "haptic/softhand/sparse_direct.hpp"

namespace haptic::softhand {
namespace {

constexpr int kBlocks = 4;
constexpr int kDofs = 3 * kBlocks;

// A dense symmetric matrix on a pattern of every block but (0, 3) and (3, 0), which stay zero.
struct BlockSystem {
    BlockPattern pattern;
    std::vector<double> values;
    Eigen::MatrixXd dense;
};

BlockSystem makeSystem(const Eigen::MatrixXd& symmetric) {
    BlockSystem out;
    std::vector<std::pair<int, int>> blocks;
    for (int r = 0; r < kBlocks; ++r) {
        for (int c = 0; c < kBlocks; ++c) {
            if (!((r == 0 && c == 3) || (r == 3 && c == 0))) {
                blocks.emplace_back(r, c);
            }
        }
    }
    out.pattern.build(kBlocks, blocks);
    out.values.assign(9 * static_cast<std::size_t>(out.pattern.blockCount()), 0.0);
    out.dense = Eigen::MatrixXd::Zero(kDofs, kDofs);
    for (int r = 0; r < kBlocks; ++r) {
        for (int block = out.pattern.rowBegin(r); block < out.pattern.rowEnd(r); ++block) {
            const int c = out.pattern.column(block);
            for (int i = 0; i < 3; ++i) {
                for (int j = 0; j < 3; ++j) {
                    const double v = symmetric(3 * r + i, 3 * c + j);
                    out.values[9 * static_cast<std::size_t>(block) + 3 * i + j] = v;
                    out.dense(3 * r + i, 3 * c + j) = v;
                }
            }
        }
    }
    return out;
}

Eigen::MatrixXd positiveDefinite() {
    std::srand(7);
    const Eigen::MatrixXd a = Eigen::MatrixXd::Random(kDofs, kDofs);
    return a * a.transpose() + kDofs * Eigen::MatrixXd::Identity(kDofs, kDofs);
}

TEST(SparseDirectSolver, MatchesADenseSolveOnTheFreeDofs) {
    const BlockSystem system = makeSystem(positiveDefinite());
    std::srand(11);
    const Eigen::VectorXd b = Eigen::VectorXd::Random(kDofs);
    std::vector<char> free_mask(kDofs, 1);
    free_mask[4] = 0;  // a pinned DoF: x stays 0 there, its column drops out
    free_mask[9] = 0;

    Eigen::MatrixXd reduced = system.dense;
    Eigen::VectorXd reduced_b = b;
    for (int i : {4, 9}) {
        reduced.row(i).setZero();
        reduced.col(i).setZero();
        reduced(i, i) = 1.0;
        reduced_b(i) = 0.0;
    }
    const Eigen::VectorXd expected = reduced.ldlt().solve(reduced_b);

    SparseDirectSolver solver;
    Eigen::VectorXd x;
    ASSERT_TRUE(solver.solve(system.pattern, system.values, b, free_mask, x));
    EXPECT_LT((x - expected).norm(), 1e-10 * expected.norm());
    EXPECT_EQ(x(4), 0.0);
    EXPECT_EQ(x(9), 0.0);

    // Same pattern, new values: only the numeric factorisation is redone, still exact.
    const BlockSystem scaled = makeSystem(2.0 * positiveDefinite());
    ASSERT_TRUE(solver.solve(scaled.pattern, scaled.values, b, free_mask, x));
    EXPECT_LT((x - 0.5 * expected).norm(), 1e-10 * expected.norm());
}

// The pattern grows (a contact coupling a node to a new body does this within a step): the
// solver must analyse the new structure, not reuse the old ordering on it.
TEST(SparseDirectSolver, AnalysesAGrownPatternAnew) {
    BlockSystem system = makeSystem(positiveDefinite());
    const std::vector<char> free_mask(kDofs, 1);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(kDofs, 1.0, 2.0);
    SparseDirectSolver solver;
    Eigen::VectorXd x;
    ASSERT_TRUE(solver.solve(system.pattern, system.values, b, free_mask, x));

    // The same BlockPattern object, rebuilt with the two missing blocks, now non-zero.
    std::vector<std::pair<int, int>> blocks{{0, 3}, {3, 0}};
    system.pattern.appendBlocks(blocks);
    system.pattern.build(kBlocks, blocks);
    Eigen::MatrixXd coupled = system.dense;
    coupled.block<3, 3>(0, 9) = 0.5 * Eigen::Matrix3d::Identity();
    coupled.block<3, 3>(9, 0) = 0.5 * Eigen::Matrix3d::Identity();
    system.values.assign(9 * static_cast<std::size_t>(system.pattern.blockCount()), 0.0);
    for (int r = 0; r < kBlocks; ++r) {
        for (int block = system.pattern.rowBegin(r); block < system.pattern.rowEnd(r); ++block) {
            const int c = system.pattern.column(block);
            for (int i = 0; i < 3; ++i) {
                for (int j = 0; j < 3; ++j) {
                    system.values[9 * static_cast<std::size_t>(block) + 3 * i + j] =
                        coupled(3 * r + i, 3 * c + j);
                }
            }
        }
    }
    ASSERT_TRUE(solver.solve(system.pattern, system.values, b, free_mask, x));
    const Eigen::VectorXd expected = coupled.ldlt().solve(b);
    EXPECT_LT((x - expected).norm(), 1e-10 * expected.norm());
}

TEST(SparseDirectSolver, RefusesAnIndefiniteSystemAndLeavesXAlone) {
    Eigen::MatrixXd indefinite = positiveDefinite();
    indefinite(5, 5) = -1e3;
    const BlockSystem system = makeSystem(indefinite);
    const std::vector<char> free_mask(kDofs, 1);
    Eigen::VectorXd x = Eigen::VectorXd::Constant(kDofs, 3.0);
    SparseDirectSolver solver;
    EXPECT_FALSE(
        solver.solve(system.pattern, system.values, Eigen::VectorXd::Ones(kDofs), free_mask, x));
    EXPECT_EQ(x, Eigen::VectorXd::Constant(kDofs, 3.0));
}

TEST(SparseDirectSolver, AgreesWithPcgRunToConvergence) {
    const BlockSystem system = makeSystem(positiveDefinite());
    const std::vector<char> free_mask(kDofs, 1);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(kDofs, -1.0, 1.0);
    BlockJacobiPreconditioner preconditioner;
    preconditioner.compute(system.pattern, system.values, kBlocks, free_mask);
    PcgWorkspace work;
    Eigen::VectorXd pcg_x = Eigen::VectorXd::Zero(kDofs);
    const PcgResult pcg = solvePcg(system.pattern, system.values, b, free_mask, preconditioner, 500,
                                   1e-12, pcg_x, work);
    ASSERT_TRUE(pcg.converged);
    SparseDirectSolver solver;
    Eigen::VectorXd direct_x;
    ASSERT_TRUE(solver.solve(system.pattern, system.values, b, free_mask, direct_x));
    EXPECT_LT((direct_x - pcg_x).norm(), 1e-9 * direct_x.norm());
}

// A fingertip pressed onto a table for 0.1 s: the step with the direct solver ends where the
// step with PCG run to 1e-10 ends (both directions are the Newton direction to roundoff; the
// PCG run's warm start and extra cold halvings do not change where the iterations converge),
// and needs no PCG iteration.
TEST(SparseDirectSolver, StepsAFingertipPressAsConvergedPcgDoes) {
    config::HandConfig hand;
    hand.model = config::HandModel::kFingertip;
    hand.finger = config::Finger::kIndex;
    hand.resolution = 0;
    hand.anthropometry = {0.19, 0.085, 0.016};
    const auto run = [&](LinearSolver linear_solver, int* pcg_iterations) {
        SolverSettings settings;
        settings.linear_solver = linear_solver;
        settings.pcg_max_iterations = 5000;
        settings.pcg_relative_tolerance = 1e-10;
        HandModel model = buildHand(hand, settings);
        const int table = model.simulation.addCollider(
            {HalfSpace{}, Vec3(0.0, 0.0, -0.009), Mat3::Identity(), 0.6});
        const int bone = model.bones.front().body;
        const Vec3 start = model.simulation.bodyPosition(bone);
        *pcg_iterations = 0;
        for (int step = 1; step <= 20; ++step) {
            model.simulation.setTrackingTarget(bone, start - Vec3(0.0, 0.0, 0.00025 * step),
                                               Mat3::Identity());
            *pcg_iterations += model.simulation.step(0.005).pcg_iterations;
        }
        return std::pair{model.simulation.forceOnCollider(table).z(),
                         model.simulation.bodyPosition(bone)};
    };
    int pcg_iterations = 0;
    int direct_pcg_iterations = 0;
    const auto [pcg_force, pcg_bone] = run(LinearSolver::kPcg, &pcg_iterations);
    const auto [direct_force, direct_bone] = run(LinearSolver::kSparseLdlt, &direct_pcg_iterations);
    EXPECT_GT(pcg_iterations, 0);
    EXPECT_EQ(direct_pcg_iterations, 0);
    ASSERT_LT(pcg_force, -0.05);  // it pressed
    EXPECT_NEAR(direct_force, pcg_force, 1e-3 * std::fabs(pcg_force));
    EXPECT_LT((direct_bone - pcg_bone).norm(), 1e-7);
}

}  // namespace
}  // namespace haptic::softhand
