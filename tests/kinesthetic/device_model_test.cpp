#include "haptic/kinesthetic/device_model.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "haptic/config/device.hpp"

namespace haptic::kinesthetic {
namespace {

config::ExoskeletonConfig shippedExoskeleton() {
    return config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/exoskeleton.yaml")
        .exoskeleton();
}

ConfigVector pose(double a, double b, double c) {
    ConfigVector q(3);
    q << a, b, c;
    return q;
}

TEST(ExoskeletonDevice, ActuationMatrixIsTheGradientOfTheClosure) {
    const ExoskeletonDevice sut(shippedExoskeleton());
    for (const ConfigVector& q :
         {pose(0.0, 0.0, 0.0), pose(0.7, 0.4, 0.2), pose(1.4, 1.7, 1.2), pose(-0.3, 0.9, 0.6)}) {
        ActuationMatrix B;
        sut.actuationMatrix(q, B);
        ASSERT_EQ(B.rows(), 3);
        ASSERT_EQ(B.cols(), 1);
        for (int j = 0; j < 3; ++j) {
            const double h = 1e-6;
            ConfigVector qp = q;
            ConfigVector qm = q;
            qp[j] += h;
            qm[j] -= h;
            ActuatorVector lp;
            ActuatorVector lm;
            sut.actuatorCoordinates(qp, lp);
            sut.actuatorCoordinates(qm, lm);
            EXPECT_NEAR(B(j, 0), (lp[0] - lm[0]) / (2 * h), 1e-8) << "joint " << j;
        }
    }
}

TEST(ExoskeletonDevice, StrokeGrowsWithFlexionAcrossTheShippedJointLimits) {
    const auto exo = shippedExoskeleton();
    const ExoskeletonDevice sut(exo);
    ActuatorVector extended;
    ActuatorVector flexed;
    const auto& limits = exo.finger.joint_limits_rad;
    sut.actuatorCoordinates(pose(limits[0].min, limits[1].min, limits[2].min), extended);
    sut.actuatorCoordinates(pose(limits[0].max, limits[1].max, limits[2].max), flexed);
    EXPECT_GT(flexed[0], extended[0]);
    // The yaml documents "about 2 mm (extended) to 23 mm (fully flexed)".
    EXPECT_NEAR(extended[0], 0.002, 0.0015);
    EXPECT_NEAR(flexed[0], 0.023, 0.003);
    EXPECT_DOUBLE_EQ(sut.actuatorLimits(0).max_force_n, exo.actuator.max_force_n);
    EXPECT_TRUE(sut.isUnderactuated());
}

// finger.phalanx_lengths_m, shipped and with a longer middle phalanx.
TEST(ExoskeletonDevice, StraightFingerTipIsTheSumOfThePhalanges) {
    auto longer = shippedExoskeleton();
    longer.finger.phalanx_lengths_m[1] += 0.005;
    for (const auto& exo : {shippedExoskeleton(), longer}) {
        const ExoskeletonDevice sut(exo);
        PointVector x;
        sut.contactPoint(pose(0.0, 0.0, 0.0), x);
        const auto& lengths = exo.finger.phalanx_lengths_m;
        EXPECT_NEAR(x[0], lengths[0] + lengths[1] + lengths[2], 1e-15);
        EXPECT_NEAR(x[1], 0.0, 1e-15);
    }
}

// The stroke of a planar rod from the actuator's base pivot to the attachment on the proximal
// phalanx, turned with it, plus the distal couplings; built with Eigen's rotation, not the
// device model's own lever.
double strokeByGeometry(const config::LinkageConfig& linkage, const ConfigVector& q) {
    const Eigen::Vector2d attachment =
        Eigen::Rotation2Dd(q[0]) *
        Eigen::Vector2d(linkage.proximal_attachment_m[0], linkage.proximal_attachment_m[1]);
    const Eigen::Vector2d base(linkage.actuator_base_m[0], linkage.actuator_base_m[1]);
    return (attachment - base).norm() - linkage.rod_length_m +
           linkage.distal_coupling_m_per_rad[0] * q[1] +
           linkage.distal_coupling_m_per_rad[1] * q[2];
}

// Every linkage key, changed alone: the device model's stroke follows the geometry's.
TEST(ExoskeletonDevice, EachLinkageKeyMovesTheStrokeAsTheGeometrySays) {
    const auto shipped = shippedExoskeleton();
    std::vector<config::ExoskeletonConfig> variants(5, shipped);
    variants[0].linkage.actuator_base_m[0] -= 0.004;
    variants[1].linkage.proximal_attachment_m[1] += 0.003;
    variants[2].linkage.rod_length_m += 0.001;
    variants[3].linkage.distal_coupling_m_per_rad[0] *= 2.0;
    variants[4].linkage.distal_coupling_m_per_rad[1] *= 2.0;
    for (const ConfigVector& q : {pose(0.0, 0.0, 0.0), pose(0.7, 0.4, 0.2), pose(1.2, 1.5, 1.0)}) {
        ActuatorVector stroke_shipped;
        ExoskeletonDevice(shipped).actuatorCoordinates(q, stroke_shipped);
        EXPECT_NEAR(stroke_shipped[0], strokeByGeometry(shipped.linkage, q), 1e-12);
        for (std::size_t v = 0; v < variants.size(); ++v) {
            ActuatorVector stroke;
            ExoskeletonDevice(variants[v]).actuatorCoordinates(q, stroke);
            EXPECT_NEAR(stroke[0], strokeByGeometry(variants[v].linkage, q), 1e-12) << v;
            if (v == 2) {
                EXPECT_NEAR(stroke[0] - stroke_shipped[0], -0.001, 1e-12) << "a longer rod";
            }
            if (v == 0 || v == 1 || q[1] + q[2] > 0.0) {
                EXPECT_GT(std::abs(stroke[0] - stroke_shipped[0]), 1e-5) << v;
            }
        }
    }
}

TEST(ExoskeletonDevice, RejectsNonPositivePhalanx) {
    auto exo = shippedExoskeleton();
    exo.finger.phalanx_lengths_m[1] = 0.0;
    EXPECT_THROW(ExoskeletonDevice{exo}, std::invalid_argument);
}

TEST(LinearPointDevice, MapsActuatedDirectionsAndRejectsBadOnes) {
    Eigen::MatrixXd A(3, 2);
    A << 1, 0, 0, 1, 0, 0;
    const LinearPointDevice sut(A, 20.0);
    EXPECT_EQ(sut.dofs(), 3);
    EXPECT_EQ(sut.actuators(), 2);
    ConfigVector q(3);
    q << 0.1, 0.2, 0.3;
    ActuatorVector ell;
    sut.actuatorCoordinates(q, ell);
    EXPECT_DOUBLE_EQ(ell[0], 0.1);
    EXPECT_DOUBLE_EQ(ell[1], 0.2);

    Eigen::MatrixXd parallel(2, 2);
    parallel << 1, 2, 1, 2;
    EXPECT_THROW(LinearPointDevice(parallel, 1.0), std::invalid_argument);
    Eigen::MatrixXd nan_direction(2, 1);
    nan_direction << std::nan(""), 1;
    EXPECT_THROW(LinearPointDevice(nan_direction, 1.0), std::invalid_argument);
    EXPECT_THROW(LinearPointDevice(Eigen::MatrixXd::Identity(4, 1), 1.0), std::invalid_argument);
    EXPECT_THROW(LinearPointDevice(Eigen::MatrixXd::Identity(2, 1), 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace haptic::kinesthetic
