#pragma once

// Anisotropic tracking impedance (docs/algorithms.md §6.5-6.7): K = k_a P_a + rho k_a P_u, and how
// to choose rho. All functions are noexcept, allocation-free and bounded, so the 1 kHz loop may
// call them.
//
// Single plane n^T y >= 0 (n any length), user = spring K_u pulling towards an intent x_u
// inside the wall, quasi-static equilibrium K_u (x_u - x) + f_r(x) = 0 with the rendered
// force f_r = kappa' (-n^T x) P_a n, kappa' = 1 / (n^T K^-1 n). By Sherman-Morrison,
//   x = x_u - kappa' K_u^-1 P_a n (n^T x_u) / (1 + kappa' gamma),  gamma = n^T K_u^-1 P_a n,
// so n^T x = n^T x_u / (1 + kappa' gamma): the equilibrium depends on the intent only through
// its depth, and
//   f_r       = kappa' / (1 + kappa' gamma)  * (-n^T x_u) P_a n
//   P_a F_full = k_a / (1 + k_a eta)          * (-n^T x_u) P_a n,   eta = n^T K_u^-1 n.
// Both lie along P_a n, so the ghost force g = f_r - P_a F_full vanishes iff
//   kappa' = k_a / (1 + k_a (eta - gamma)),  i.e. with |n| = 1, c^2 = |P_a n|^2, s^2 = |P_u n|^2:
//   rho* = s^2 / (s^2 + k_a n^T K_u^-1 P_u n)                                      (*)
// For K_u = k_u I this is rho* = k_u / (k_u + k_a), the [DER] result of §6.6. (*) is our
// generalisation; it has no positive root when s^2 + k_a n^T K_u^-1 P_u n <= 0 (strongly
// anisotropic K_u), which is why the run-time path uses the bounded numeric search and (*)
// only serves as a cross-check in the tests.

#include "haptic/kinesthetic/types.hpp"

namespace haptic::kinesthetic {

inline constexpr double kMinRho = 1e-6;  // keeps K SPD (docs/algorithms.md §6.8 step 3)
inline constexpr double kMaxRho = 1e6;   // "infinity": the subspace-proxy limit

// §6.6: rho* = k_u / (k_u + k_a) for an isotropic user stiffness; clamped to [kMinRho, 1].
[[nodiscard]] double optimalRhoIsotropic(double k_a, double k_u) noexcept;

// (*) above; NaN when there is no positive root or an input is invalid.
[[nodiscard]] double optimalRhoAnisotropicUser(const ConfigMatrix& P_a, double k_a,
                                               const ConfigMatrix& K_u,
                                               const ConfigVector& normal) noexcept;

// |f_r(rho) - P_a F_full| for the canonical intent one unit deep along -n/|n| (the ratio to
// the depth is depth independent). NaN on invalid input.
[[nodiscard]] double ghostForceMismatch(const ConfigMatrix& P_a, double k_a,
                                        const ConfigMatrix& K_u, const ConfigVector& normal,
                                        double rho) noexcept;

struct RhoSearchResult {
    double rho{1.0};
    double mismatch{0.0};  // ghostForceMismatch at rho
    int evaluations{0};
    bool valid{false};  // false: invalid input, rho left at 1 (naive)
};

// §6.7: golden-section search of ghostForceMismatch over log(rho) in [kMinRho, kMaxRho] with
// exactly `iterations` shrink steps (the bracket shrinks by 0.618 per step).
[[nodiscard]] RhoSearchResult searchOptimalRho(const ConfigMatrix& P_a, double k_a,
                                               const ConfigMatrix& K_u, const ConfigVector& normal,
                                               int iterations = 48) noexcept;

// Closed forms of §6.4-6.6 for one wall and isotropic user stiffness: intent depth_u inside
// the wall, constraint normal at angle beta from the actuated subspace (cos_beta = c).
struct SingleWallPrediction {
    double full_force{0.0};        // |F_full|
    double rendered_force{0.0};    // |f_r(rho)|
    double normal_force{0.0};      // F_n(rho)
    double tangential_force{0.0};  // F_t(rho)
    double ghost_force{0.0};       // |f_r - P_a F_full|
    double force_error{0.0};       // |f_r - F_full|
};

[[nodiscard]] SingleWallPrediction predictSingleWall(double k_a, double k_u, double depth_u,
                                                     double cos_beta, double rho) noexcept;

}  // namespace haptic::kinesthetic
