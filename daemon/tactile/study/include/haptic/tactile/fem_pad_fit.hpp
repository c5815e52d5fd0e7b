#pragma once

// The optimiser's pad law fitted to the soft-hand FEM (docs/algorithms.md §3.7, issue #21):
// the flat plate presses the FEM fingertip at several depths, and the optimiser's own force
// model for that plate pose, F(delta) = c sum_i w_i s (exp(delta_i / s) - 1) over the pad
// samples handsim sends that lie under the plate (w_i their linear-pad area weights, delta_i
// how far the plate is past sample i), is fitted to the FEM's force: the stiffening depth s
// and the scale c. s is what the optimiser needs (optimiser.pad_stiffening_depth_m; a global
// scale does not move its optimum); c says how much stiffer the FEM pad is than the linear
// pad's weights. Offline.

#include <vector>

#include "haptic/tactile/fem_error_analysis.hpp"

namespace haptic::tactile {

struct PadIndentation {
    double depth_m{0.0};        // the flat plate past the undeformed pad's lowest point
    double fem_force_n{0.0};    // the FEM's normal force on the finger
    double model_force_n{0.0};  // the fitted law's
};

struct PadLawFit {
    double stiffening_depth_m{0.0};  // s, at most 0.1 m (the config key's range)
    // s at the top of its range: the FEM's force grows linearly with the plate's depth (its
    // tissue is co-rotated linear, and a flat plate on the pad's round section widens the
    // contact about as fast as it deepens), so the optimiser's law is as linear as it can be.
    bool linear{false};
    double weight_scale{0.0};        // c
    double rms_relative_error{0.0};  // of model against FEM force over the depths
    double max_relative_error{0.0};
    std::vector<PadIndentation> points;
};

// The depths used by default: 0.25 mm to 2 mm, the thimble's working range (its force limit,
// 1.5 N, is reached near 1.5 mm on the FEM pad at level 1).
[[nodiscard]] std::vector<double> defaultPadFitDepths();

// Presses the flat, untilted plate at each depth and fits (s, c) by least squares on relative
// force error: c in closed form for each s, s by a log-spaced scan and a golden-section
// refinement, within (0.1 mm, 0.1 m). Throws std::runtime_error when a press finds no contact.
[[nodiscard]] PadLawFit fitPadLawToFem(const FemFingertip& finger, double plate_radius_m,
                                       const std::vector<double>& depths_m);

}  // namespace haptic::tactile
