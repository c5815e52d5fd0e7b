#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "contact_rows.hpp"
#include "haptic/config/device.hpp"
#include "haptic/kinesthetic/anisotropic.hpp"
#include "haptic/kinesthetic/port_safety.hpp"
#include "haptic/kinesthetic/renderer.hpp"

namespace haptic::kinesthetic {
namespace {

// The 1 kHz path: renderer tick (every method and rho mode, msgs constraints), rho search and
// the port guard, on the exoskeleton with 4 active constraints, must not touch the heap.
TEST(KinestheticAllocation, RenderingTickAndPortGuardAllocateNothing) {
    const auto exo_config =
        config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/exoskeleton.yaml");
    const ExoskeletonDevice exo(exo_config.exoskeleton());
    RenderParameters p;
    p.tracking_stiffness = 2.0;
    p.actuator_damping = 0.5;
    KinestheticRenderer renderer(exo, p);
    PortGuardConfig guard_config;
    ActuatorPortGuard guard(guard_config);

    std::array<msgs::LinearConstraint, 4> constraints{};
    const double normals[4][3] = {{-1, 0, -0.2}, {-1, 0, -1}, {-1, -0.5, -0.3}, {-0.2, 0, -1}};
    ConfigVector q(3);
    q << 0.6, 0.9, 0.5;
    for (std::size_t j = 0; j < 4; ++j) {
        double dot = 0.0;
        for (std::size_t i = 0; i < 3; ++i) {
            constraints[j].a[i] = normals[j][i];
            dot += normals[j][i] * q[static_cast<Eigen::Index>(i)];
        }
        constraints[j].b = dot + 0.02;  // all four violated
    }
    ConfigVector q_dot(3);
    q_dot << 0.1, -0.2, 0.05;
    RenderOutput out;
    ActuatorVector ell;
    const RhoMode modes[] = {RhoMode::kClosedForm, RhoMode::kNumericSearch, RhoMode::kManual};
    const RenderingMethod methods[] = {
        RenderingMethod::kStandard,           RenderingMethod::kNaive,
        RenderingMethod::kNullspace,          RenderingMethod::kSubspace,
        RenderingMethod::kLinearizedSubspace, RenderingMethod::kAnisotropic};
    int ticks = 0;
    std::uint64_t allocations = 0;
    {
        testing::ScopedAllocationCounter counter;
        for (const auto mode : modes) {
            RenderParameters changed = p;
            changed.rho_mode = mode;
            // setParameters is not on the loop but must not allocate either (run-time switch).
            ASSERT_EQ(renderer.setParameters(changed), nullptr);
            for (const auto method : methods) {
                renderer.setMethod(method);
                for (int k = 0; k < 60; ++k) {
                    q[1] += (k % 2 == 0 ? 1e-4 : -1e-4);
                    renderer.tick(q, q_dot, constraints, out);
                    exo.actuatorCoordinates(q, ell);
                    (void)guard.apply(out.actuator_force[0], ell[0], k % 20 != 0);
                    ++ticks;
                }
            }
        }
        allocations = counter.allocations();
    }
    EXPECT_EQ(allocations, 0U);
    EXPECT_EQ(ticks, 3 * 6 * 60);

    // Rows that carry their contact: subspace solves each along the actuator (bounded Newton),
    // linearized_subspace re-linearises it; every method evaluates them.
    for (std::size_t j = 0; j < 4; ++j) {
        msgs::ContactKinematics& c = constraints[j].contact;
        c.joints = 3;
        c.gap_m = -0.002 * static_cast<double>(j + 1);
        c.normal = {normals[j][0], normals[j][1], 0.3};
        for (std::size_t k = 0; k < 3; ++k) {
            c.q_ref_rad[k] = q[static_cast<Eigen::Index>(k)];
            c.axis[k] = {0.0, 0.0, 1.0};
            c.lever_m[k] = {0.02 * static_cast<double>(3 - k), 0.01, 0.0};
        }
    }
    int contact_ticks = 0;
    {
        testing::ScopedAllocationCounter counter;
        for (const auto method : methods) {
            renderer.setMethod(method);
            for (int k = 0; k < 60; ++k) {
                q[1] += (k % 2 == 0 ? 1e-4 : -1e-4);
                renderer.tick(q, q_dot, constraints, out);
                ++contact_ticks;
            }
        }
        allocations = counter.allocations();
    }
    EXPECT_EQ(allocations, 0U);
    EXPECT_EQ(contact_ticks, 6 * 60);
    EXPECT_TRUE(out.actuator_force.allFinite());
    EXPECT_TRUE(out.actuator_force.allFinite());
}

// nullspace's redistribution (§5.3) runs only with two or more active contacts that share a
// resultant: the middle phalanx and the fingertip on one face (NullspaceRendering.Splits...).
TEST(KinestheticAllocation, NullspaceRedistributionAllocatesNothing) {
    const config::ExoskeletonConfig exo_config =
        config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/exoskeleton.yaml")
            .exoskeleton();
    const ExoskeletonDevice exo(exo_config);
    ConfigVector q(3);
    q << 0.5, 0.7, 0.4;
    const std::array<msgs::LinearConstraint, 2> rows{
        testing::phalanxContact(exo_config, q, 1, 0.6, 0.0018, 2.6),
        testing::phalanxContact(exo_config, q, 2, 1.0, 0.003, 2.6)};
    RenderParameters p;
    p.tracking_stiffness = 2.0;
    p.method = RenderingMethod::kNaive;
    KinestheticRenderer naive(exo, p);
    p.method = RenderingMethod::kNullspace;
    KinestheticRenderer renderer(exo, p);
    const ConfigVector q_dot = ConfigVector::Zero(3);
    RenderOutput naive_out;
    RenderOutput out;
    naive.tick(q, q_dot, rows, naive_out);
    renderer.tick(q, q_dot, rows, out);  // warm-up
    std::size_t allocations = 0;
    {
        testing::ScopedAllocationCounter counter;
        for (int k = 0; k < 60; ++k) {
            renderer.tick(q, q_dot, rows, out);
        }
        allocations = counter.allocations();
    }
    EXPECT_EQ(allocations, 0U);
    ASSERT_EQ(out.active_constraints, 2);
    EXPECT_NE(out.actuator_force[0], naive_out.actuator_force[0]) << "the redistribution ran";
}

}  // namespace
}  // namespace haptic::kinesthetic
