#include "haptic/kinesthetic/anisotropic.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

namespace haptic::kinesthetic {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The rho-independent parts of the single-plane equilibrium (see the header).
struct PlaneTerms {
    double c2{0.0};     // |P_a n|^2 / |n|^2
    double s2{0.0};     // |P_u n|^2 / |n|^2
    double gamma{0.0};  // n^T K_u^-1 P_a n / |n|^2
    double eta{0.0};    // n^T K_u^-1 n / |n|^2
    double scale{0.0};  // |P_a n| |n|, turns the scalar mismatch into a force per depth
    bool valid{false};
};

PlaneTerms planeTerms(const ConfigMatrix& P_a, const ConfigMatrix& K_u,
                      const ConfigVector& normal) noexcept {
    PlaneTerms terms;
    const auto n = normal.size();
    if (n == 0 || P_a.rows() != n || P_a.cols() != n || K_u.rows() != n || K_u.cols() != n ||
        !P_a.allFinite() || !K_u.allFinite() || !normal.allFinite()) {
        return terms;
    }
    const double norm = normal.norm();
    if (!(norm > 0.0)) {
        return terms;
    }
    const ConfigVector unit = normal / norm;
    const Eigen::LDLT<ConfigMatrix> ldlt(K_u);
    const double k_scale = K_u.diagonal().cwiseAbs().maxCoeff();
    if (ldlt.info() != Eigen::Success || !(k_scale > 0.0) ||
        ldlt.vectorD().minCoeff() <= 1e-14 * k_scale) {
        return terms;
    }
    const ConfigVector pa_n = P_a * unit;
    const ConfigVector ku_inv_n = ldlt.solve(unit);
    terms.c2 = pa_n.squaredNorm();
    terms.s2 = std::max(0.0, 1.0 - terms.c2);
    terms.gamma = ku_inv_n.dot(pa_n);  // K_u symmetric: n^T K_u^-1 P_a n
    terms.eta = ku_inv_n.dot(unit);
    terms.scale = std::sqrt(terms.c2);
    terms.valid = std::isfinite(terms.gamma) && std::isfinite(terms.eta);
    return terms;
}

double mismatch(const PlaneTerms& t, double k_a, double rho) noexcept {
    const double kappa = k_a / (t.c2 + t.s2 / rho);
    const double rendered = kappa / (1.0 + kappa * t.gamma);
    const double target = k_a / (1.0 + k_a * t.eta);
    return std::abs(rendered - target) * t.scale;
}

}  // namespace

double optimalRhoIsotropic(double k_a, double k_u) noexcept {
    if (!(k_a > 0.0) || !(k_u > 0.0) || !std::isfinite(k_a) || !std::isfinite(k_u)) {
        return kNaN;
    }
    return std::clamp(k_u / (k_u + k_a), kMinRho, 1.0);
}

double optimalRhoAnisotropicUser(const ConfigMatrix& P_a, double k_a, const ConfigMatrix& K_u,
                                 const ConfigVector& normal) noexcept {
    const PlaneTerms t = planeTerms(P_a, K_u, normal);
    if (!t.valid || !(k_a > 0.0)) {
        return kNaN;
    }
    // n^T K_u^-1 P_u n = eta - gamma.
    const double denominator = t.s2 + k_a * (t.eta - t.gamma);
    if (!(t.s2 > 0.0) || !(denominator > 0.0)) {
        return kNaN;
    }
    return t.s2 / denominator;
}

double ghostForceMismatch(const ConfigMatrix& P_a, double k_a, const ConfigMatrix& K_u,
                          const ConfigVector& normal, double rho) noexcept {
    const PlaneTerms t = planeTerms(P_a, K_u, normal);
    if (!t.valid || !(k_a > 0.0) || !(rho > 0.0)) {
        return kNaN;
    }
    return mismatch(t, k_a, rho);
}

RhoSearchResult searchOptimalRho(const ConfigMatrix& P_a, double k_a, const ConfigMatrix& K_u,
                                 const ConfigVector& normal, int iterations) noexcept {
    RhoSearchResult result;
    const PlaneTerms t = planeTerms(P_a, K_u, normal);
    if (!t.valid || !(k_a > 0.0) || !std::isfinite(k_a)) {
        return result;
    }
    const double inv_phi = (std::sqrt(5.0) - 1.0) / 2.0;
    double lo = std::log(kMinRho);
    double hi = std::log(kMaxRho);
    double x1 = hi - inv_phi * (hi - lo);
    double x2 = lo + inv_phi * (hi - lo);
    double f1 = mismatch(t, k_a, std::exp(x1));
    double f2 = mismatch(t, k_a, std::exp(x2));
    int evaluations = 2;
    for (int i = 0; i < iterations; ++i) {
        if (f1 <= f2) {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - inv_phi * (hi - lo);
            f1 = mismatch(t, k_a, std::exp(x1));
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + inv_phi * (hi - lo);
            f2 = mismatch(t, k_a, std::exp(x2));
        }
        ++evaluations;
    }
    const double best = f1 <= f2 ? x1 : x2;
    result.rho = std::exp(best);
    result.mismatch = std::min(f1, f2);
    result.evaluations = evaluations;
    result.valid = std::isfinite(result.mismatch);
    if (!result.valid) {
        result.rho = 1.0;
    }
    return result;
}

SingleWallPrediction predictSingleWall(double k_a, double k_u, double depth_u, double cos_beta,
                                       double rho) noexcept {
    SingleWallPrediction p;
    const double c = std::clamp(std::abs(cos_beta), 0.0, 1.0);
    const double c2 = c * c;
    const double s2 = 1.0 - c2;
    const double s = std::sqrt(s2);
    p.full_force = k_a * k_u * depth_u / (k_u + k_a);
    // rho = inf (subspace proxy) is the limit s^2 / rho -> 0.
    const double s2_over_rho = std::isinf(rho) ? 0.0 : s2 / rho;
    const double denominator = k_u * (c2 + s2_over_rho) + k_a * c2;
    const double along = k_a * k_u * depth_u / denominator;  // f_r = along * P_a n
    p.rendered_force = along * c;
    p.normal_force = along * c2;
    p.tangential_force = along * c * s;
    p.ghost_force = std::abs(p.rendered_force - p.full_force * c);
    // F_full = |F_full| n; f_r has normal part F_n and tangential part F_t.
    p.force_error = std::hypot(p.full_force - p.normal_force, p.tangential_force);
    return p;
}

}  // namespace haptic::kinesthetic
