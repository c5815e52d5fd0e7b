#include "haptic/softhand/pcg.hpp"

#include <Eigen/Cholesky>
#include <cmath>

namespace haptic::softhand {

void BlockJacobiPreconditioner::compute(const SparseMatrix& a,
                                        const std::vector<std::pair<int, int>>& blocks,
                                        const std::vector<char>& free_mask) {
    blocks_ = blocks;
    inverses_.resize(blocks.size());
    for (std::size_t bi = 0; bi < blocks.size(); ++bi) {
        const auto [start, size] = blocks[bi];
        Eigen::MatrixXd block = Eigen::MatrixXd::Zero(size, size);
        for (int r = 0; r < size; ++r) {
            for (SparseMatrix::InnerIterator it(a, start + r); it; ++it) {
                const auto col = static_cast<int>(it.col());
                if (col >= start && col < start + size) {
                    block(r, col - start) = it.value();
                }
            }
        }
        for (int r = 0; r < size; ++r) {
            if (free_mask[start + r] == 0) {
                block.row(r).setZero();
                block.col(r).setZero();
                block(r, r) = 1.0;
            }
        }
        const Eigen::LDLT<Eigen::MatrixXd> ldlt(block);
        if (ldlt.info() == Eigen::Success && ldlt.isPositive() &&
            (ldlt.vectorD().array() > 0.0).all()) {
            inverses_[bi] = ldlt.solve(Eigen::MatrixXd::Identity(size, size));
        } else {
            // Not SPD (should not happen with the Gauss-Newton blocks): plain Jacobi.
            Eigen::VectorXd diag = block.diagonal().cwiseAbs().cwiseMax(1e-300);
            inverses_[bi] = diag.cwiseInverse().asDiagonal();
        }
    }
}

void BlockJacobiPreconditioner::apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
    for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
        const auto [start, size] = blocks_[bi];
        z.segment(start, size).noalias() = inverses_[bi] * r.segment(start, size);
    }
}

PcgResult solvePcg(const SparseMatrix& a, const Eigen::VectorXd& b,
                   const std::vector<char>& free_mask, const BlockJacobiPreconditioner& pre,
                   int max_iterations, double relative_tolerance, Eigen::VectorXd& x) {
    const auto n = b.size();
    Eigen::VectorXd mask(n);
    for (Eigen::Index i = 0; i < n; ++i) {
        mask(i) = free_mask[static_cast<std::size_t>(i)] != 0 ? 1.0 : 0.0;
    }
    PcgResult result;
    const double b_norm = b.cwiseProduct(mask).norm();
    if (b_norm == 0.0) {
        x.setZero();
        result.converged = true;
        return result;
    }
    x = x.cwiseProduct(mask);
    Eigen::VectorXd r = (b - a * x).cwiseProduct(mask);
    if (!(r.norm() < b_norm)) {
        // The warm start is worse than nothing (the system changed a lot): start from zero.
        x.setZero();
        r = b.cwiseProduct(mask);
    }
    Eigen::VectorXd z(n);
    pre.apply(r, z);
    z = z.cwiseProduct(mask);
    Eigen::VectorXd p = z;
    Eigen::VectorXd ap(n);
    double rz = r.dot(z);
    const double target = relative_tolerance * b_norm;
    double r_norm = r.norm();
    // With an iteration cap the last iterate is not always the best one; keep the best.
    Eigen::VectorXd best = x;
    double best_norm = r_norm;
    while (r_norm > target && result.iterations < max_iterations) {
        ap.noalias() = a * p;
        ap = ap.cwiseProduct(mask);
        const double curvature = p.dot(ap);
        if (!(curvature > 0.0)) {
            break;  // lost positive definiteness numerically; keep the iterate we have
        }
        const double alpha = rz / curvature;
        x += alpha * p;
        r -= alpha * ap;
        r_norm = r.norm();
        ++result.iterations;
        if (r_norm < best_norm) {
            best = x;
            best_norm = r_norm;
        }
        pre.apply(r, z);
        z = z.cwiseProduct(mask);
        const double rz_next = r.dot(z);
        p = z + (rz_next / rz) * p;
        rz = rz_next;
    }
    x = best;
    result.relative_residual = best_norm / b_norm;
    result.converged = best_norm <= target;
    return result;
}

}  // namespace haptic::softhand
