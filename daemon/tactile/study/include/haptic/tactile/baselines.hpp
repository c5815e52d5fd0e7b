#pragma once

// Baselines the contact optimiser is compared with (docs/algorithms.md §3.7, [REC]). Both return
// platform DoFs projected into the workspace; both need at least one contact sample.
//
// (a) geometricPlaneFit: the plate on the plane through the weighted centroid of the contact
//     points (projected onto the virtual object) with the weighted average object normal.
// (b) forceNormalDisplacement: the plate normal along the virtual force, pressed
//     |F| / k_finger past the plane that just touches the undeformed pad samples; the
//     quasi-static linear finger model of the cable-driven predecessor.

#include <Eigen/Core>
#include <optional>

#include "haptic/msgs/messages.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::tactile {

[[nodiscard]] std::optional<PlatformDofs> geometricPlaneFit(const ThimbleKinematics& kinematics,
                                                            const msgs::ContactSurface& surface);

[[nodiscard]] std::optional<PlatformDofs> forceNormalDisplacement(
    const ThimbleKinematics& kinematics, const msgs::ContactSurface& surface,
    const Eigen::Vector3d& force_on_finger_n, double finger_stiffness_n_per_m);

}  // namespace haptic::tactile
