#pragma once

// Scenes shared by the fast validation tests and the fine (Release-only) ones.

#include <array>
#include <string>

#include "haptic/softhand/simulation.hpp"

namespace haptic::softhand {

// The two solver settings every validation runs at. kConverged: the test's own (the static
// tests solve PCG to 1e-9-1e-10; the incline tests keep SolverSettings' PCG, 200 iterations to
// 1e-4) with SolverSettings' Newton, halving and substep limits. kShipped: handsim's real-time
// limits from realtimeSceneSettings() on top (PCG cap 30 at 1e-4, one Newton iteration, 2
// halvings, no substeps), the solver as it ships; quasi-static tests give it more relax steps.
enum class SolverProfile { kConverged, kShipped };
[[nodiscard]] SolverSettings withProfile(SolverSettings settings, SolverProfile profile);
// Relax steps for a quasi-static test: `converged` at kConverged, 40x that at kShipped (each
// step is one capped Newton step from rest).
[[nodiscard]] int relaxSteps(int converged, SolverProfile profile);
[[nodiscard]] std::string profileName(SolverProfile profile);

// Cantilever 0.1 x 0.01 x 0.01 m clamped at x = 0, tip load on the x = L face; returns the
// mean tip deflection divided by Euler-Bernoulli's P L^3 / (3 E I).
double cantileverTipDeflectionRatio(std::array<int, 3> cells,
                                    SolverProfile profile = SolverProfile::kConverged);

// Rigid sphere (R = 10 mm) into a block, quarter model with `cells` graded cells per axis
// (ratio `grading`, block side `width_m`); returns F / F_Hertz at the given indentation.
double hertzForceRatio(int cells, double grading, double width_m, double indentation_m,
                       SolverProfile profile = SolverProfile::kConverged);

}  // namespace haptic::softhand
