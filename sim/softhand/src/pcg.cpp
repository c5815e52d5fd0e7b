#include "haptic/softhand/pcg.hpp"

#include <Eigen/Cholesky>
#include <cmath>

namespace haptic::softhand {

namespace {

using RowBlock = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;

// Inverse of an SPD block; plain Jacobi when it is not SPD (should not happen with the
// Gauss-Newton blocks).
template <int N>
Eigen::Matrix<double, N, N> invertBlock(Eigen::Matrix<double, N, N> block, const char* free) {
    for (int r = 0; r < N; ++r) {
        if (free[r] == 0) {
            block.row(r).setZero();
            block.col(r).setZero();
            block(r, r) = 1.0;
        }
    }
    const Eigen::LDLT<Eigen::Matrix<double, N, N>> ldlt(block);
    if (ldlt.info() == Eigen::Success && ldlt.isPositive() &&
        (ldlt.vectorD().array() > 0.0).all()) {
        return ldlt.solve(Eigen::Matrix<double, N, N>::Identity());
    }
    const Eigen::Matrix<double, N, 1> diag = block.diagonal().cwiseAbs().cwiseMax(1e-300);
    return diag.cwiseInverse().asDiagonal();
}

}  // namespace

void BlockJacobiPreconditioner::compute(const BlockPattern& pattern,
                                        const std::vector<double>& values, int node_count,
                                        const std::vector<char>& free_mask) {
    const int body_count = (pattern.blockRows() - node_count) / 2;
    node_inverses_.resize(static_cast<std::size_t>(node_count));
    body_inverses_.resize(static_cast<std::size_t>(body_count));
    for (int i = 0; i < node_count; ++i) {
        const Eigen::Matrix3d block = RowBlock(values.data() + 9 * pattern.diagonal(i));
        node_inverses_[i] = invertBlock<3>(block, free_mask.data() + 3 * i);
    }
    for (int b = 0; b < body_count; ++b) {
        const int first = node_count + 2 * b;
        Mat6 block = Mat6::Zero();
        for (int r = 0; r < 2; ++r) {
            for (int c = 0; c < 2; ++c) {
                const int k = pattern.find(first + r, first + c);
                if (k >= 0) {
                    block.block<3, 3>(3 * r, 3 * c) = RowBlock(values.data() + 9 * k);
                }
            }
        }
        body_inverses_[b] = invertBlock<6>(block, free_mask.data() + 3 * first);
    }
}

void BlockJacobiPreconditioner::apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
    const auto nodes = static_cast<Eigen::Index>(node_inverses_.size());
    for (Eigen::Index i = 0; i < nodes; ++i) {
        z.segment<3>(3 * i).noalias() = node_inverses_[i] * r.segment<3>(3 * i);
    }
    for (std::size_t b = 0; b < body_inverses_.size(); ++b) {
        const Eigen::Index start = 3 * nodes + 6 * static_cast<Eigen::Index>(b);
        z.segment<6>(start).noalias() = body_inverses_[b] * r.segment<6>(start);
    }
}

void PcgWorkspace::resize(Eigen::Index n) {
    for (Eigen::VectorXd* v : {&mask, &r, &z, &p, &ap, &best}) {
        v->resize(n);
    }
}

PcgResult solvePcg(const BlockPattern& pattern, const std::vector<double>& values,
                   const Eigen::VectorXd& b, const std::vector<char>& free_mask,
                   const BlockJacobiPreconditioner& pre, int max_iterations,
                   double relative_tolerance, Eigen::VectorXd& x, PcgWorkspace& work,
                   const std::atomic<bool>* stop) {
    const auto n = b.size();
    work.resize(n);
    Eigen::VectorXd& mask = work.mask;
    Eigen::VectorXd& r = work.r;
    Eigen::VectorXd& z = work.z;
    Eigen::VectorXd& p = work.p;
    Eigen::VectorXd& ap = work.ap;
    for (Eigen::Index i = 0; i < n; ++i) {
        mask(i) = free_mask[static_cast<std::size_t>(i)] != 0 ? 1.0 : 0.0;
    }
    PcgResult result;
    r = b.cwiseProduct(mask);
    const double b_norm = r.norm();
    if (b_norm == 0.0) {
        x.setZero();
        result.converged = true;
        return result;
    }
    x = x.cwiseProduct(mask);
    pattern.multiply(values, x, ap);
    r = (b - ap).cwiseProduct(mask);
    if (!(r.norm() < b_norm)) {
        // The warm start is worse than nothing (the system changed a lot): start from zero.
        x.setZero();
        r = b.cwiseProduct(mask);
    }
    pre.apply(r, z);
    z = z.cwiseProduct(mask);
    p = z;
    double rz = r.dot(z);
    const double target = relative_tolerance * b_norm;
    double r_norm = r.norm();
    // With an iteration cap the iterate kept is the one with the lowest quadratic model
    // q(x) = 1/2 x^T A x - b^T x = -(b + r)^T x / 2, which is what the Newton step needs: a
    // lower q is a longer descent along the merit's model. CG lowers q at every iteration, but
    // not always the residual norm: keeping the smallest residual instead returned the start
    // (x = 0, no step at all) for a cantilever whose residual rose over the first 30
    // iterations, and froze it.
    Eigen::VectorXd& best = work.best;
    best = x;
    double best_norm = r_norm;
    double best_model = -0.5 * (b + r).dot(x);
    while (r_norm > target && result.iterations < max_iterations &&
           (stop == nullptr || !stop->load(std::memory_order_relaxed))) {
        pattern.multiply(values, p, ap);
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
        const double model = -0.5 * (b + r).dot(x);
        if (model < best_model) {
            best = x;
            best_norm = r_norm;
            best_model = model;
        }
        pre.apply(r, z);
        z = z.cwiseProduct(mask);
        const double rz_next = r.dot(z);
        p = z + (rz_next / rz) * p;
        rz = rz_next;
    }
    if (r_norm <= target) {
        // Converged: the last iterate. Near convergence the model falls by less than its
        // rounding, and an earlier iterate could otherwise win on noise.
        best = x;
        best_norm = r_norm;
    }
    x = best;
    result.relative_residual = best_norm / b_norm;
    result.converged = best_norm <= target;
    return result;
}

}  // namespace haptic::softhand
