#pragma once

// Device model of docs/algorithms.md §4: configuration q (n), actuator coordinates ell = sigma(q)
// (m), actuation matrix B(q) = (d sigma / dq)^T (n x m), contact point x = chi(q) (d) and its
// Jacobian J = d chi / dq (d x n), and the limits of q and of the actuators.
//
// Contract: every query is const, noexcept and allocation-free, so the 1 kHz loop may call
// it. Out-parameters are resized to their run-time size; nothing else is touched.

#include <string>
#include <vector>

#include "haptic/config/device.hpp"
#include "haptic/kinesthetic/types.hpp"

namespace haptic::kinesthetic {

struct ActuatorLimits {
    double max_force_n{0.0};  // |u| <= this (N for linear actuators)
    double stroke_min{0.0};   // ell range (m for linear actuators)
    double stroke_max{0.0};
};

class DeviceModel {
  public:
    virtual ~DeviceModel() = default;

    [[nodiscard]] virtual int dofs() const noexcept = 0;       // n
    [[nodiscard]] virtual int actuators() const noexcept = 0;  // m <= n
    [[nodiscard]] virtual int pointDim() const noexcept = 0;   // d, 2 or 3

    virtual void actuatorCoordinates(const ConfigVector& q, ActuatorVector& ell) const noexcept = 0;
    virtual void actuationMatrix(const ConfigVector& q, ActuationMatrix& B) const noexcept = 0;
    virtual void contactPoint(const ConfigVector& q, PointVector& x) const noexcept = 0;

    [[nodiscard]] virtual ActuatorLimits actuatorLimits(int actuator) const noexcept = 0;
    // Joint (or workspace) bounds of coordinate i of q.
    [[nodiscard]] virtual config::Interval configurationLimits(int i) const noexcept = 0;

    [[nodiscard]] bool isUnderactuated() const noexcept { return actuators() < dofs(); }

  protected:
    DeviceModel() = default;
    DeviceModel(const DeviceModel&) = default;
    DeviceModel& operator=(const DeviceModel&) = default;
};

// The synthetic device of the chapter 6 experiments (docs/algorithms.md §6.1, §6.10): q = x in R^d,
// d = 2 or 3, and the actuators push along the columns of A (d x m, any m <= d), so
// sigma(q) = A^T q, B = A, chi(q) = q, J = I. A = I gives the fully actuated reference.
class LinearPointDevice final : public DeviceModel {
  public:
    // Throws std::invalid_argument if d is not 2 or 3, A is empty, rank deficient, has more
    // columns than d, has non-finite entries, or a limit is not positive.
    LinearPointDevice(const Eigen::MatrixXd& actuated_directions, double max_force_n,
                      double workspace_half_width_m = 0.5);

    [[nodiscard]] int dofs() const noexcept override { return static_cast<int>(A_.rows()); }
    [[nodiscard]] int actuators() const noexcept override { return static_cast<int>(A_.cols()); }
    [[nodiscard]] int pointDim() const noexcept override { return dofs(); }
    void actuatorCoordinates(const ConfigVector& q, ActuatorVector& ell) const noexcept override;
    void actuationMatrix(const ConfigVector& q, ActuationMatrix& B) const noexcept override;
    void contactPoint(const ConfigVector& q, PointVector& x) const noexcept override;
    [[nodiscard]] ActuatorLimits actuatorLimits(int actuator) const noexcept override;
    [[nodiscard]] config::Interval configurationLimits(int i) const noexcept override;

  private:
    BoundedMatrix<kMaxPointDim, kMaxPointDim> A_;
    double max_force_n_;
    double half_width_m_;
};

// The underactuated finger exoskeleton of docs/algorithms.md §5.8: a planar 3R finger
// q = (theta_mcp, theta_pip, theta_dip), fingertip x = sum_k L_k (cos phi_k, sin phi_k) with
// phi_k = theta_1 + ... + theta_k, driven by one linear actuator through the dorsal linkage
// whose assumed closure is documented in haptic/config/device.hpp (LinkageConfig):
//   sigma(q) = |R(theta_1) p - a| - rod + c_pip theta_2 + c_dip theta_3
//   b(q)     = ( (R(theta_1) p - a)^T R'(theta_1) p / |R(theta_1) p - a|, c_pip, c_dip )
// The values come from config/devices/exoskeleton.yaml, so a lab enters its CAD values there.
class ExoskeletonDevice final : public DeviceModel {
  public:
    // Throws std::invalid_argument on non-positive lengths or forces, or a linkage whose
    // actuator pivots coincide.
    explicit ExoskeletonDevice(const config::ExoskeletonConfig& exo);

    [[nodiscard]] int dofs() const noexcept override { return 3; }
    [[nodiscard]] int actuators() const noexcept override { return 1; }
    [[nodiscard]] int pointDim() const noexcept override { return 2; }
    void actuatorCoordinates(const ConfigVector& q, ActuatorVector& ell) const noexcept override;
    void actuationMatrix(const ConfigVector& q, ActuationMatrix& B) const noexcept override;
    void contactPoint(const ConfigVector& q, PointVector& x) const noexcept override;
    [[nodiscard]] ActuatorLimits actuatorLimits(int actuator) const noexcept override;
    [[nodiscard]] config::Interval configurationLimits(int i) const noexcept override;

    [[nodiscard]] const config::ExoskeletonConfig& parameters() const noexcept { return exo_; }

  private:
    config::ExoskeletonConfig exo_;
};

}  // namespace haptic::kinesthetic
