#pragma once

// Small rotation and decomposition helpers shared by the energy terms (docs/algorithms.md
// §1.1-1.2).

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>

namespace haptic::softhand {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

[[nodiscard]] inline Mat3 skew(const Vec3& a) {
    Mat3 s;
    s << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
    return s;
}

// exp([w]x) via the angle-axis form; exact for any angle.
[[nodiscard]] inline Mat3 expMap(const Vec3& w) {
    const double angle = w.norm();
    if (angle < 1e-12) {
        return Mat3::Identity() + skew(w);
    }
    return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

// log(R)^v, the rotation vector (axis * angle) of a rotation matrix.
[[nodiscard]] inline Vec3 logMap(const Mat3& rotation) {
    const Eigen::AngleAxisd aa(rotation);
    return aa.axis() * aa.angle();
}

// Re-orthonormalises a rotation that drifted through repeated products.
[[nodiscard]] inline Mat3 orthonormalized(const Mat3& rotation) {
    return Eigen::Quaterniond(rotation).normalized().toRotationMatrix();
}

// Rotation of the polar decomposition F = R S (det F > 0) by Higham's scaled Newton
// iteration X <- (zeta X + X^-T / zeta) / 2: quadratic convergence, a handful of iterations
// for the moderately deformed elements of a step and no trigonometry, which made the
// eigen-decomposition path the largest cost of the energy check. The scale is the Frobenius
// one, zeta = (|X^-1| / |X|)^(1/2) (two square roots; the determinant scaling's cube root
// was a fifth of the step), and is dropped once X is near orthogonal, where it is 1 anyway.
// Returns false (and leaves `rotation` alone) when det F <= 0 or it does not converge;
// callers then take the SVD.
[[nodiscard]] inline bool highamPolarRotation(const Mat3& f, Mat3& rotation) {
    Mat3 x = f;
    bool scaled = true;
    for (int iteration = 0; iteration < 16; ++iteration) {
        Mat3 cofactor;
        cofactor.col(0) = x.col(1).cross(x.col(2));
        cofactor.col(1) = x.col(2).cross(x.col(0));
        cofactor.col(2) = x.col(0).cross(x.col(1));
        const double det = x.col(0).dot(cofactor.col(0));
        if (!(det > 0.0) || !std::isfinite(det)) {
            return false;
        }
        // X^-T = cofactor / det.
        const double zeta =
            scaled ? std::sqrt(std::sqrt(cofactor.squaredNorm() / x.squaredNorm()) / det) : 1.0;
        const Mat3 next = 0.5 * (zeta * x + cofactor * (1.0 / (zeta * det)));
        const double change = (next - x).squaredNorm();
        x = next;
        // Quadratic convergence: a step of 1e-6 leaves an error of order 1e-12, and the
        // energy is stationary in R at the polar rotation, so its error is of order 1e-24.
        if (change < 1e-12) {
            rotation = x;
            return true;
        }
        scaled = change > 1e-6;
    }
    return false;
}

// Rotation of the polar decomposition of F. Nearly every element of a step is within a
// few percent of a rotation, and there the Newton-Schulz iteration X <- X (3 I - X^T X) / 2
// converges quadratically with products only (no division or square root, whose dependent
// latencies made the scaled Newton iteration above 110 ns however small the strain); it needs
// det F > 0 and |F^T F - I| < 1/2 (every singular value in [0.7, 1.23]), else the scaled
// Newton iteration takes over. Returns false (and leaves `rotation` alone) when det F <= 0 or
// F is not finite; callers then take the SVD.
[[nodiscard]] inline bool polarRotation(const Mat3& f, Mat3& rotation) {
    const double det = f.col(0).dot(f.col(1).cross(f.col(2)));
    if (!(det > 0.0)) {
        return false;
    }
    Mat3 x = f;
    for (int iteration = 0; iteration < 8; ++iteration) {
        // E = X^T X - I (symmetric) and X <- X - X E / 2, written out: Eigen's generic 3x3
        // products measured slower here than the scalar form.
        const Vec3 c0 = x.col(0);
        const Vec3 c1 = x.col(1);
        const Vec3 c2 = x.col(2);
        const double e00 = c0.dot(c0) - 1.0;
        const double e11 = c1.dot(c1) - 1.0;
        const double e22 = c2.dot(c2) - 1.0;
        const double e01 = c0.dot(c1);
        const double e02 = c0.dot(c2);
        const double e12 = c1.dot(c2);
        const double error =
            e00 * e00 + e11 * e11 + e22 * e22 + 2.0 * (e01 * e01 + e02 * e02 + e12 * e12);
        if (!(error < 0.25)) {
            return highamPolarRotation(f, rotation);
        }
        x.col(0) = c0 - 0.5 * (e00 * c0 + e01 * c1 + e02 * c2);
        x.col(1) = c1 - 0.5 * (e01 * c0 + e11 * c1 + e12 * c2);
        x.col(2) = c2 - 0.5 * (e02 * c0 + e12 * c1 + e22 * c2);
        // The update squares the error: from |X^T X - I| < 1e-6 it leaves about 1e-12.
        if (error < 1e-12) {
            rotation = x;
            return true;
        }
    }
    return highamPolarRotation(f, rotation);
}

// Inversion-safe SVD F = U diag(sigma) V^T with U, V proper rotations: when det F < 0 the
// smallest singular value carries the sign (Irving et al. 2004), so an inverted element
// reports sigma_min < 0 and the strain-limit penalty pushes it back out.
struct RotationVariantSvd {
    Mat3 u;
    Vec3 sigma;
    Mat3 v;

    [[nodiscard]] Mat3 rotation() const { return u * v.transpose(); }
};

[[nodiscard]] inline RotationVariantSvd jacobiRotationVariantSvd(const Mat3& f) {
    const Eigen::JacobiSVD<Mat3> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
    RotationVariantSvd out{svd.matrixU(), svd.singularValues(), svd.matrixV()};
    if (out.u.determinant() < 0.0) {
        out.u.col(2) *= -1.0;
        out.sigma(2) *= -1.0;
    }
    if (out.v.determinant() < 0.0) {
        out.v.col(2) *= -1.0;
        out.sigma(2) *= -1.0;
    }
    return out;
}

// Closed-form path (eigen-decomposition of F^T F), several times faster than JacobiSVD,
// which dominated the step time. Falls back to JacobiSVD for inverted elements and when
// a singular value is close to zero, where F^T F loses the precision.
[[nodiscard]] inline RotationVariantSvd rotationVariantSvd(const Mat3& f) {
    Eigen::SelfAdjointEigenSolver<Mat3> eigen;
    eigen.computeDirect(f.transpose() * f);
    const Vec3 lambda = eigen.eigenvalues();  // ascending
    // Inverted or nearly flat elements take the careful path.
    if (!(f.determinant() > 0.0) || !(lambda(2) > 0.0) || !(lambda(0) > 1e-8 * lambda(2)) ||
        !lambda.allFinite()) {
        return jacobiRotationVariantSvd(f);
    }
    RotationVariantSvd out;
    out.v.col(0) = eigen.eigenvectors().col(2);
    out.v.col(1) = eigen.eigenvectors().col(1);
    out.v.col(2) = out.v.col(0).cross(out.v.col(1));  // proper rotation
    out.sigma(0) = std::sqrt(lambda(2));
    out.sigma(1) = std::sqrt(lambda(1));
    out.u.col(0) = (f * out.v.col(0)).normalized();
    Vec3 u1 = f * out.v.col(1);
    u1 -= out.u.col(0).dot(u1) * out.u.col(0);
    out.u.col(1) = u1.normalized();
    out.u.col(2) = out.u.col(0).cross(out.u.col(1));
    // Signed: negative when F is inverted, since U and V are both proper rotations.
    out.sigma(2) = out.u.col(2).dot(f * out.v.col(2));
    if (!out.u.allFinite() || !out.v.allFinite()) {
        return jacobiRotationVariantSvd(f);
    }
    return out;
}

}  // namespace haptic::softhand
