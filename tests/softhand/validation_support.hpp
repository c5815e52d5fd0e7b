#pragma once

// Scenes shared by the fast validation tests and the fine (Release-only) ones.

#include <array>

namespace haptic::softhand {

// Cantilever 0.1 x 0.01 x 0.01 m clamped at x = 0, tip load on the x = L face; returns the
// mean tip deflection divided by Euler-Bernoulli's P L^3 / (3 E I).
double cantileverTipDeflectionRatio(std::array<int, 3> cells);

// Rigid sphere (R = 10 mm) into a block, quarter model with `cells` graded cells per axis
// (ratio `grading`, block side `width_m`); returns F / F_Hertz at the given indentation.
double hertzForceRatio(int cells, double grading, double width_m, double indentation_m);

}  // namespace haptic::softhand
