#include "haptic/kinesthetic/kmetric_projection.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace haptic::kinesthetic {

namespace {

using SmallMatrix = BoundedMatrix<kMaxDofs, kMaxDofs>;
using SmallVector = BoundedVector<kMaxDofs>;

// Relative size below which a pivot or Schur complement counts as zero (dependent normals).
constexpr double kDependenceTolerance = 1e-10;
constexpr double kFeasibilityTolerance = 1e-12;

void removeAt(ActiveSet& set, int position) noexcept {
    for (int i = position; i + 1 < set.size; ++i) {
        set.index[static_cast<std::size_t>(i)] = set.index[static_cast<std::size_t>(i + 1)];
    }
    --set.size;
}

int at(const ActiveSet& set, int i) noexcept {
    return set.index[static_cast<std::size_t>(i)];
}

// Q restricted to the active set and h on it, both scaled by S = diag(Q_jj)^-1/2 so that the
// dependence test does not depend on how differently the constraints are scaled (K can have a
// condition number of 1e12 when rho is tiny or huge).
void gather(const ConstraintGram& Q, const ConstraintVector& h, const ActiveSet& set,
            SmallMatrix& Q_pp, SmallVector& h_p, SmallVector& scale) noexcept {
    Q_pp.resize(set.size, set.size);
    h_p.resize(set.size);
    scale.resize(set.size);
    for (int r = 0; r < set.size; ++r) {
        scale[r] = 1.0 / std::sqrt(Q(at(set, r), at(set, r)));
    }
    for (int r = 0; r < set.size; ++r) {
        h_p[r] = h[at(set, r)] * scale[r];
        for (int c = 0; c < set.size; ++c) {
            Q_pp(r, c) = Q(at(set, r), at(set, c)) * scale[r] * scale[c];
        }
    }
}

// Solves Q_pp s = h_p; false if Q_pp is (numerically) singular, i.e. dependent normals.
bool solveActive(const ConstraintGram& Q, const ConstraintVector& h, const ActiveSet& set,
                 SmallVector& s) noexcept {
    SmallMatrix Q_pp;
    SmallVector h_p;
    SmallVector scale;
    if (set.size == 0) {
        s.resize(0);
        return true;
    }
    gather(Q, h, set, Q_pp, h_p, scale);
    const Eigen::LDLT<SmallMatrix> ldlt(Q_pp);
    if (!scale.allFinite() || ldlt.vectorD().minCoeff() <= kDependenceTolerance) {
        return false;
    }
    s = ldlt.solve(h_p).cwiseProduct(scale);
    return s.allFinite();
}

}  // namespace

const char* toString(SolveStatus status) noexcept {
    switch (status) {
        case SolveStatus::kOptimal:
            return "optimal";
        case SolveStatus::kIterationLimit:
            return "iteration limit reached";
        case SolveStatus::kInfeasible:
            return "constraints are infeasible";
        case SolveStatus::kInvalidInput:
            return "invalid input (NaN/Inf, K not SPD or size mismatch)";
    }
    return "unknown";
}

bool ActiveSet::contains(int j) const noexcept {
    for (int i = 0; i < size; ++i) {
        if (index[static_cast<std::size_t>(i)] == j) {
            return true;
        }
    }
    return false;
}

KMetricProjector::KMetricProjector(int max_iterations) noexcept
    : max_iterations_(std::max(1, max_iterations)) {}

ProjectionResult KMetricProjector::project(const ConfigMatrix& K, const ConfigVector& y0,
                                           const ConstraintMatrix& C, const ConstraintVector& d,
                                           const ActiveSet& warm_start, ConfigVector& y) noexcept {
    ProjectionResult result;
    const int n = static_cast<int>(y0.size());
    const int count = static_cast<int>(C.cols());
    y = y0;
    if (n == 0 || K.rows() != n || K.cols() != n || C.rows() != n || d.size() != count ||
        !K.allFinite() || !y0.allFinite() || !C.allFinite() || !d.allFinite()) {
        return result;
    }
    const Eigen::LDLT<ConfigMatrix> k_ldlt(K);
    const double k_scale = K.diagonal().cwiseAbs().maxCoeff();
    if (k_ldlt.info() != Eigen::Success || !(k_scale > 0.0) ||
        k_ldlt.vectorD().minCoeff() <= 1e-14 * k_scale) {
        return result;
    }

    const ConstraintMatrix Kinv_C = k_ldlt.solve(C);
    const ConstraintGram Q = C.transpose() * Kinv_C;
    const ConstraintVector h = d - C.transpose() * y0;
    const ConstraintVector norm = C.colwise().norm().transpose();
    ConstraintVector lambda = ConstraintVector::Zero(count);
    const double y_scale = 1.0 + y0.cwiseAbs().maxCoeff();

    bool infeasible = false;
    for (int j = 0; j < count; ++j) {
        if (norm[j] <= 1e-300 && d[j] > 0.0) {
            infeasible = true;  // 0 >= d_j > 0 can never hold
        }
    }

    // Warm start: keep the previous active constraints that still push (s > 0).
    ActiveSet active;
    for (int i = 0; i < warm_start.size && active.size < n; ++i) {
        const int j = at(warm_start, i);
        if (j >= 0 && j < count && norm[j] > 1e-300 && !active.contains(j)) {
            active.index[static_cast<std::size_t>(active.size++)] = static_cast<std::int16_t>(j);
        }
    }
    SmallVector s;
    while (active.size > 0) {
        if (!solveActive(Q, h, active, s)) {
            removeAt(active, active.size - 1);
            continue;
        }
        int worst = -1;
        for (int i = 0; i < active.size; ++i) {
            if (s[i] <= 0.0 && (worst < 0 || s[i] < s[worst])) {
                worst = i;
            }
        }
        if (worst < 0) {
            for (int i = 0; i < active.size; ++i) {
                lambda[at(active, i)] = s[i];
            }
            break;
        }
        removeAt(active, worst);
    }

    int iterations = 0;
    bool optimal = false;
    while (iterations < max_iterations_) {
        ++iterations;
        const ConstraintVector violation = h - Q * lambda;  // d_j - c_j^T y
        int entering = -1;
        double largest = 0.0;
        for (int j = 0; j < count; ++j) {
            if (norm[j] <= 1e-300 || active.contains(j)) {
                continue;
            }
            const double v = violation[j] / norm[j];
            if (v > kFeasibilityTolerance * y_scale && v > largest) {
                largest = v;
                entering = j;
            }
        }
        if (entering < 0) {
            optimal = true;
            break;
        }

        // Is the entering normal dependent on the active ones (in the K^-1 metric)?
        SmallVector mu;
        bool dependent = active.size >= n;
        if (active.size > 0) {
            SmallMatrix Q_pp;
            SmallVector unused;
            SmallVector scale;
            SmallVector q_pj(active.size);
            gather(Q, h, active, Q_pp, unused, scale);
            const double entering_scale = 1.0 / std::sqrt(Q(entering, entering));
            for (int i = 0; i < active.size; ++i) {
                q_pj[i] = Q(at(active, i), entering) * scale[i] * entering_scale;
            }
            const Eigen::LDLT<SmallMatrix> ldlt(Q_pp);
            const SmallVector mu_scaled = ldlt.solve(q_pj);
            // Schur complement of the scaled Gram matrix: 1 - cos^2 of the angle between the
            // entering normal and the span of the active ones.
            const double schur = 1.0 - q_pj.dot(mu_scaled);
            dependent = dependent || schur <= kDependenceTolerance;
            // c_entering = sum_i mu_i c_i in unscaled terms.
            mu = mu_scaled.cwiseProduct(scale) / entering_scale;
        }
        if (dependent) {
            // Goldfarb-Idnani partial step: shift multiplier from the active constraints that
            // span the entering one until one of them leaves; y stays put.
            int leaving = -1;
            double t = 0.0;
            for (int i = 0; i < active.size; ++i) {
                if (mu[i] > 1e-12) {
                    const double ratio = lambda[at(active, i)] / mu[i];
                    if (leaving < 0 || ratio < t) {
                        t = ratio;
                        leaving = i;
                    }
                }
            }
            if (leaving < 0) {
                infeasible = true;  // the entering constraint opposes the active ones
                break;
            }
            for (int i = 0; i < active.size; ++i) {
                lambda[at(active, i)] -= t * mu[i];
            }
            lambda[at(active, leaving)] = 0.0;
            lambda[entering] = t;
            active.index[static_cast<std::size_t>(leaving)] = static_cast<std::int16_t>(entering);
        } else {
            active.index[static_cast<std::size_t>(active.size++)] =
                static_cast<std::int16_t>(entering);
        }

        // Lawson-Hanson inner loop: move towards the equality solution on the active set,
        // dropping constraints whose multiplier would turn negative.
        while (active.size > 0 && iterations < max_iterations_) {
            if (!solveActive(Q, h, active, s)) {
                infeasible = true;
                break;
            }
            bool all_positive = true;
            double alpha = 1.0;
            for (int i = 0; i < active.size; ++i) {
                if (s[i] <= 0.0) {
                    all_positive = false;
                    const double l = lambda[at(active, i)];
                    alpha = std::min(alpha, l / (l - s[i]));
                }
            }
            if (all_positive) {
                for (int i = 0; i < active.size; ++i) {
                    lambda[at(active, i)] = s[i];
                }
                break;
            }
            ++iterations;
            for (int i = 0; i < active.size; ++i) {
                double& l = lambda[at(active, i)];
                l += alpha * (s[i] - l);
            }
            for (int i = active.size - 1; i >= 0; --i) {
                if (lambda[at(active, i)] <= 1e-15 * (1.0 + lambda.cwiseAbs().maxCoeff())) {
                    lambda[at(active, i)] = 0.0;
                    removeAt(active, i);
                }
            }
        }
        if (infeasible) {
            break;
        }
    }

    y = y0 + Kinv_C * lambda;
    const ConstraintVector final_violation = d - C.transpose() * y;
    double worst = 0.0;
    for (int j = 0; j < count; ++j) {
        if (norm[j] > 1e-300) {
            worst = std::max(worst, final_violation[j] / norm[j]);
        }
    }
    result.max_violation = worst;
    result.iterations = iterations;
    result.active = active;
    if (!y.allFinite()) {
        y = y0;
        result.status = SolveStatus::kInvalidInput;
    } else if (infeasible) {
        result.status = SolveStatus::kInfeasible;
    } else {
        result.status = optimal ? SolveStatus::kOptimal : SolveStatus::kIterationLimit;
    }
    return result;
}

}  // namespace haptic::kinesthetic
