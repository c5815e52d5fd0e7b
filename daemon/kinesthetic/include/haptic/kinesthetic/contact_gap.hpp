#pragma once

// A constraint row's contact evaluated on the finger's kinematics (msgs::ContactKinematics,
// docs/algorithms.md §5.4): g(q) = normal . (x(q) - p) + gap_m, with x(q) the contact point p
// carried from q_ref_rad to q by the joints behind it, as a product of exponentials of their
// rotations. The row's a and b are g's linearisation at q_ref_rad; subspace solves g itself
// along the actuated direction, linearized_subspace linearises it at the current q.
//
// RT: noexcept, no allocation, O(joints).

#include "haptic/kinesthetic/types.hpp"
#include "haptic/msgs/messages.hpp"

namespace haptic::kinesthetic {

// Whether `contact` can be evaluated on a device with `dofs` joints: 1 <= joints <=
// min(kMaxContactJoints, dofs), everything finite, the normal and each axis non-zero.
[[nodiscard]] bool usableContact(const msgs::ContactKinematics& contact, int dofs) noexcept;

// g(q) (m); when `gradient` is given, dg/dq into it (size of q, zero beyond the joints).
// Call only on a usable contact.
[[nodiscard]] double contactGap(const msgs::ContactKinematics& contact, const ConfigVector& q,
                                ConfigVector* gradient = nullptr) noexcept;

}  // namespace haptic::kinesthetic
