#pragma once

// Fixed-capacity Eigen types for the kinesthetic renderer. Every matrix has a compile-time
// maximum size and a run-time size, so nothing on the 1 kHz path touches the heap.

#include <Eigen/Core>

#include "haptic/msgs/capacities.hpp"

namespace haptic::kinesthetic {

inline constexpr int kMaxDofs = static_cast<int>(msgs::kMaxJointDofs);       // n, configuration
inline constexpr int kMaxActuators = static_cast<int>(msgs::kMaxActuators);  // m, actuators
inline constexpr int kMaxPointDim = 3;                                       // contact point
inline constexpr int kMaxConstraintCount = static_cast<int>(msgs::kMaxConstraints);

template <int MaxRows, int MaxCols>
using BoundedMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, MaxRows, MaxCols>;
template <int MaxRows>
using BoundedVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, MaxRows, 1>;

using ConfigVector = BoundedVector<kMaxDofs>;                           // q, tau (n)
using ConfigMatrix = BoundedMatrix<kMaxDofs, kMaxDofs>;                 // K, P_a (n x n)
using ActuatorVector = BoundedVector<kMaxActuators>;                    // ell, u (m)
using ActuationMatrix = BoundedMatrix<kMaxDofs, kMaxActuators>;         // B (n x m)
using PointVector = BoundedVector<kMaxPointDim>;                        // x = chi(q)
using ConstraintMatrix = BoundedMatrix<kMaxDofs, kMaxConstraintCount>;  // normals, one a column
using ConstraintVector = BoundedVector<kMaxConstraintCount>;
using ConstraintGram = BoundedMatrix<kMaxConstraintCount, kMaxConstraintCount>;  // C^T K^-1 C

}  // namespace haptic::kinesthetic
