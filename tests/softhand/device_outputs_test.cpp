// Device outputs of the soft hand against geometry computed here by hand: the exoskeleton's
// linearised contact constraint (plane under a straight finger), its prediction of the gap
// after a small flexion, and the thimble's pad samples in the device frame.

#include "haptic/softhand/device_outputs.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <vector>

#include "haptic/daemon/sim_input_validation.hpp"
#include "haptic/kinesthetic/contact_gap.hpp"

namespace haptic::softhand {
namespace {

config::HandConfig handConfig(config::HandModel model) {
    config::HandConfig hand;
    hand.model = model;
    hand.finger = config::Finger::kIndex;
    hand.resolution = 1;
    hand.anthropometry = {0.19, 0.085, 0.016};
    return hand;
}

const BoneInfo& bone(const HandModel& model, const char* name) {
    const BoneInfo* found = model.findBone(name);
    EXPECT_NE(found, nullptr) << name;
    return *found;
}

// Smallest n . (x - p0) over the skin nodes of one bone: the gap to a plane.
double planeGap(const Simulation& sim, const BoneInfo& b, const Vec3& normal, const Vec3& point) {
    double gap = std::numeric_limits<double>::infinity();
    for (int node : sim.skinNodes()) {
        if (node >= b.first_node && node < b.first_node + b.node_count) {
            gap = std::min(gap, normal.dot(sim.nodePosition(node) - point));
        }
    }
    return gap;
}

// Moves every bone and its tissue rigidly to the poses (no solve).
void placeRigidly(HandModel& model, const std::vector<BonePose>& poses) {
    Simulation& sim = model.simulation;
    for (std::size_t k = 0; k < model.bones.size(); ++k) {
        const BoneInfo& b = model.bones[k];
        const Vec3 c0 = sim.bodyPosition(b.body);
        const Mat3 rotation = poses[k].rotation * sim.bodyRotation(b.body).transpose();
        for (int node = b.first_node; node < b.first_node + b.node_count; ++node) {
            sim.setNodePosition(node,
                                poses[k].position_m + rotation * (sim.nodePosition(node) - c0));
        }
        sim.setBodyPose(b.body, poses[k].position_m, poses[k].rotation);
    }
}

class KinestheticOutputTest : public ::testing::Test {
  protected:
    // A plane tilted by 0.2 rad about y, facing up and back, 1 mm below the fingertip's
    // closest skin node: only the distal phalanx is within the 3 mm margin.
    void SetUp() override {
        const double lowest =
            planeGap(model.simulation, bone(model, "index_distal"), normal, Vec3::Zero());
        point = normal * (lowest - 0.001);
        model.simulation.addCollider({HalfSpace{}, point, plane_rotation, 0.5});
    }

    static constexpr int kMaxPressSteps = 400;

    // Sets the tracking targets to the finger flexed by `dq` from its build pose and lets the
    // sim come to rest; the steps it took (kMaxPressSteps: not at rest).
    int pressTowards(const std::array<double, 3>& dq) {
        Simulation& sim = model.simulation;
        std::vector<BonePose> poses;
        kinematics.forward(kinematics.buildPose(0), dq, poses);
        for (std::size_t k = 0; k < model.bones.size(); ++k) {
            if (!sim.body(model.bones[k].body).kinematic) {
                sim.setTrackingTarget(model.bones[k].body, poses[k].position_m, poses[k].rotation);
            }
        }
        return sim.relax(0.005, kMaxPressSteps, 1e-8);
    }

    // The distal skin node nearest the plane, and its distance to it.
    std::pair<int, double> closestDistalNode() const {
        const Simulation& sim = model.simulation;
        const BoneInfo& distal = bone(model, "index_distal");
        std::pair<int, double> closest{-1, std::numeric_limits<double>::infinity()};
        for (int node : sim.skinNodes()) {
            const double gap = normal.dot(sim.nodePosition(node) - point);
            if (node >= distal.first_node && node < distal.first_node + distal.node_count &&
                gap < closest.second) {
                closest = {node, gap};
            }
        }
        return closest;
    }

    HandModel model = buildHand(handConfig(config::HandModel::kFinger), SolverSettings{});
    HandKinematics kinematics{model};
    KinestheticOutput output{model, kinematics, config::Finger::kIndex};
    Mat3 plane_rotation = Eigen::AngleAxisd(-0.2, Vec3::UnitY()).toRotationMatrix();
    Vec3 normal = plane_rotation * Vec3::UnitZ();
    Vec3 point;
};

TEST_F(KinestheticOutputTest, StraightFingerOverTiltedPlaneGivesOneHandComputedConstraint) {
    msgs::ConstraintSet set;
    output.fill(model.simulation, set);
    ASSERT_EQ(set.dof, 3);
    EXPECT_THAT(std::vector<double>(set.q_sim_rad.begin(), set.q_sim_rad.begin() + 3),
                ::testing::Each(::testing::DoubleNear(0.0, 1e-12)));
    ASSERT_EQ(set.constraints.size(), 1U);

    // Closest distal skin node and the joint anchors of the straight finger (MCP at the front
    // of the palm, then the phalanx lengths along x), flexion axis +y.
    const Simulation& sim = model.simulation;
    const auto [closest, gap] = closestDistalNode();
    EXPECT_NEAR(gap, 0.001, 1e-12);
    const auto lengths = phalanxLengths(config::Finger::kIndex, 0.19);
    const double mcp_x = 0.5 * 0.45 * 0.19;
    const std::array<double, 3> anchor_x{mcp_x, mcp_x + lengths[0],
                                         mcp_x + lengths[0] + lengths[1]};
    const Vec3 p = sim.nodePosition(closest);
    const auto& c = set.constraints[0];
    for (std::size_t j = 0; j < 3; ++j) {
        // n . (y x (p - anchor)) with y x d = (d_z, 0, -d_x).
        const Vec3 d = p - Vec3(anchor_x[j], 0.0, 0.0);
        EXPECT_NEAR(c.a[j], normal.dot(Vec3(d.z(), 0.0, -d.x())), 1e-12) << "joint " << j;
    }
    EXPECT_NEAR(c.b, -gap, 1e-12);  // a^T q >= b at q = 0 holds with 1 mm to spare
    EXPECT_LT(c.a[2], 0.0);         // flexing the DIP moves the pad into this plane

    set.header.source_id.assign("exo");
    EXPECT_EQ(daemon::validate(set, "exo", 3), daemon::InputRejection::kNone);
}

TEST_F(KinestheticOutputTest, ConstraintPredictsTheGapAfterASmallFlexion) {
    msgs::ConstraintSet set;
    output.fill(model.simulation, set);
    ASSERT_EQ(set.constraints.size(), 1U);
    const auto& c = set.constraints[0];

    const std::array<double, 3> dq{0.004, 0.006, 0.01};
    std::vector<BonePose> poses;
    kinematics.forward(kinematics.buildPose(0), dq, poses);
    placeRigidly(model, poses);
    const auto q = output.jointAngles(model.simulation);
    for (std::size_t j = 0; j < 3; ++j) {
        EXPECT_NEAR(q[j], dq[j], 1e-9);
    }
    const double predicted = c.a[0] * dq[0] + c.a[1] * dq[1] + c.a[2] * dq[2] - c.b;
    const double actual = planeGap(model.simulation, bone(model, "index_distal"), normal, point);
    EXPECT_LT(actual, 0.001 - 5e-4);  // the flexion really moved the pad towards the plane
    EXPECT_NEAR(predicted, actual, 2e-5);
}

// The row's contact (msgs::ContactKinematics) is the same constraint before linearisation:
// its gap and gradient at q_sim are the row's, and after a flexion far beyond the linear
// range it predicts where that skin point is on the plane, which the row no longer does.
TEST_F(KinestheticOutputTest, TheRowsContactPredictsTheGapBeyondTheLinearRange) {
    msgs::ConstraintSet set;
    output.fill(model.simulation, set);
    ASSERT_EQ(set.constraints.size(), 1U);
    const auto& c = set.constraints[0];
    ASSERT_EQ(c.contact.joints, 3) << "a distal contact rides on all three joints";
    ASSERT_TRUE(kinesthetic::usableContact(c.contact, 3));
    kinesthetic::ConfigVector q_sim(3);
    q_sim << set.q_sim_rad[0], set.q_sim_rad[1], set.q_sim_rad[2];
    kinesthetic::ConfigVector gradient;
    const double gap = kinesthetic::contactGap(c.contact, q_sim, &gradient);
    EXPECT_NEAR(gap, c.a[0] * q_sim[0] + c.a[1] * q_sim[1] + c.a[2] * q_sim[2] - c.b, 1e-12);
    for (std::size_t j = 0; j < 3; ++j) {
        EXPECT_NEAR(gradient[static_cast<Eigen::Index>(j)], c.a[j], 1e-12) << "joint " << j;
    }
    // The skin point the row stands for: the distal node nearest the plane.
    const int closest = closestDistalNode().first;
    const std::array<double, 3> dq{0.15, 0.25, 0.3};
    std::vector<BonePose> poses;
    kinematics.forward(kinematics.buildPose(0), dq, poses);
    placeRigidly(model, poses);
    const double actual = normal.dot(model.simulation.nodePosition(closest) - point);
    kinesthetic::ConfigVector q(3);
    q << dq[0], dq[1], dq[2];
    const double nonlinear = kinesthetic::contactGap(c.contact, q);
    const double linear = c.a[0] * dq[0] + c.a[1] * dq[1] + c.a[2] * dq[2] - c.b;
    EXPECT_NEAR(nonlinear, actual, 1e-9);
    EXPECT_GT(std::abs(linear - actual), 1e-3) << "the row alone is off by millimetres here";
}

TEST_F(KinestheticOutputTest, FarPlaneGivesNoConstraint) {
    HandModel far = buildHand(handConfig(config::HandModel::kFinger), SolverSettings{});
    far.simulation.addCollider({HalfSpace{}, Vec3(0, 0, -0.02), Mat3::Identity(), 0.5});
    const HandKinematics far_kinematics(far);
    KinestheticOutput far_output(far, far_kinematics, config::Finger::kIndex);
    msgs::ConstraintSet set;
    far_output.fill(far.simulation, set);
    EXPECT_EQ(set.constraints.size(), 0U);
}

// The generalised force of the contact forces on the finger's nodes, computed here from the
// sim's contact list: what the reference must equal once the finger rests on the object.
std::array<double, 3> contactTorques(const HandModel& model, const HandKinematics& kinematics) {
    const Simulation& sim = model.simulation;
    const FingerChain chain = *kinematics.chain(config::Finger::kIndex);
    std::array<double, 3> tau{0.0, 0.0, 0.0};
    for (const Simulation::ContactForce& contact : sim.contactForces()) {
        for (std::size_t s = 0; s < 3; ++s) {
            const BoneInfo& b = model.bones[static_cast<std::size_t>(chain.bones[s])];
            if (contact.node < b.first_node || contact.node >= b.first_node + b.node_count) {
                continue;
            }
            for (std::size_t j = 0; j <= s; ++j) {
                const Vec3 lever =
                    sim.nodePosition(contact.node) - kinematics.anchor(sim, chain.joints[j]);
                tau[j] += kinematics.axis(sim, chain.joints[j]).dot(lever.cross(contact.force_n));
            }
        }
    }
    return tau;
}

// The reference is the tracking coupling's torque. It is 0 in free space, where the springs
// hold the finger's weight and lag, and equals the contact's generalised torque once the
// finger rests on the plane pressed in by its targets.
TEST_F(KinestheticOutputTest, TheReferenceIsTheCouplingWhichMatchesTheContactAtRest) {
    Simulation& sim = model.simulation;
    ASSERT_GT(sim.settings().gravity_m_per_s2.norm(), 0.0);
    sim.relax(0.005, 50, 1e-7);  // the finger sags under its weight; no contact yet
    ASSERT_TRUE(sim.contactForces().empty());
    msgs::ConstraintSet set;
    output.fill(sim, set);
    EXPECT_THAT(set.reference_torque_nm, ::testing::Each(0.0)) << "free space renders nothing";

    // Targets flexed so that the pad would go about 2 mm into the plane.
    ASSERT_LT(pressTowards({0.02, 0.03, 0.04}), kMaxPressSteps) << "the press did not come to rest";
    ASSERT_FALSE(sim.contactForces().empty());
    output.fill(sim, set);
    const auto contact = contactTorques(model, kinematics);
    std::printf("at rest: reference %.5f %.5f %.5f N m, contact %.5f %.5f %.5f N m\n",
                set.reference_torque_nm[0], set.reference_torque_nm[1], set.reference_torque_nm[2],
                contact[0], contact[1], contact[2]);
    EXPECT_LT(contact[0], -1e-3) << "the plane pushes the finger back (extension)";
    for (std::size_t j = 0; j < 3; ++j) {
        EXPECT_NEAR(set.reference_torque_nm[j], contact[j], 0.02 * std::abs(contact[0]))
            << "joint " << j;
    }
}

// A joint pressed past its limit: the same press with the DIP's target 0.25 rad hyperextended,
// past its limit at 0, so the limit's spring carries part of what the tracking springs pull.
// That torque is the finger's own (the user's joint carries it without the device): the
// reference is still the contact's generalised torque, not the springs' (which differ from it
// at the DIP by the limit's torque).
TEST_F(KinestheticOutputTest, AJointPressedPastItsLimitLeavesTheReferenceTheContacts) {
    Simulation& sim = model.simulation;
    const FingerChain chain = *kinematics.chain(config::Finger::kIndex);
    const JointDesc& dip = sim.jointDesc(chain.joints[2]);
    ASSERT_EQ(dip.limit_min_rad, 0.0) << "the DIP does not hyperextend";
    ASSERT_LT(pressTowards({0.05, 0.05, -0.25}), kMaxPressSteps)
        << "the press did not come to rest";
    ASSERT_FALSE(sim.contactForces().empty());
    const double dip_flexion = kinematics.flexion(sim, chain.joints[2]);
    const double limit_torque = -dip.limit_stiffness_nm_per_rad * dip_flexion;
    msgs::ConstraintSet set;
    output.fill(sim, set);
    const auto contact = contactTorques(model, kinematics);
    std::printf(
        "DIP at %.4f rad (limit 0, its torque %.5f N m): reference %.5f %.5f %.5f N m, "
        "contact %.5f %.5f %.5f N m\n",
        dip_flexion, limit_torque, set.reference_torque_nm[0], set.reference_torque_nm[1],
        set.reference_torque_nm[2], contact[0], contact[1], contact[2]);
    ASSERT_LT(dip_flexion, -0.01) << "the DIP rests past its limit";
    // The limit's torque is no small part of the DIP's balance here.
    EXPECT_GT(std::abs(limit_torque), 0.5 * std::abs(contact[2]));
    for (std::size_t j = 0; j < 3; ++j) {
        EXPECT_NEAR(set.reference_torque_nm[j], contact[j], 0.02 * std::abs(contact[0]))
            << "joint " << j;
    }
}

TEST(KinestheticOutput, FingertipModelHasNoJointsForAnExoskeleton) {
    const HandModel tip = buildHand(handConfig(config::HandModel::kFingertip), SolverSettings{});
    const HandKinematics kinematics(tip);
    EXPECT_THROW(KinestheticOutput(tip, kinematics, config::Finger::kIndex), std::invalid_argument);
}

// The fingertip model's one bone as the sim has it: the tracked pose where tracking holds it.
BonePose simulatedBone(const HandModel& hand) {
    const int body = hand.bones.front().body;
    return {hand.simulation.bodyPosition(body), hand.simulation.bodyRotation(body)};
}

class TactileOutputTest : public ::testing::Test {
  protected:
    HandModel model = buildHand(handConfig(config::HandModel::kFingertip), SolverSettings{});
    // Thimble calibration: device base 12 mm from the finger frame origin towards the nail.
    config::Transform finger_from_device{{0.0, 0.0, -0.012}, {0.0, 0.0, 0.0}};
    TissueMaterial material;
    double table_z = -0.009;  // 1 mm below the 8 mm pad radius
};

TEST_F(TactileOutputTest, StraightFingertipOverTableMatchesHandGeometry) {
    model.simulation.addCollider({HalfSpace{}, Vec3(0, 0, table_z), Mat3::Identity(), 0.5});
    TactileOutputSettings settings;
    settings.max_samples = 40;
    const TactileOutput output(model, config::Finger::kIndex, finger_from_device, material,
                               settings);
    msgs::ContactSurface surface;
    output.fill(model.simulation, simulatedBone(model), surface);
    ASSERT_GT(surface.samples.size(), 5U);
    EXPECT_LE(surface.samples.size(), 40U);
    // D: origin 12 mm above the bone axis (world z = +0.012), z_D = -z_W, y_D = -y_W.
    const Vec3 centre = model.simulation.bodyPosition(model.bones.front().body);
    const double weight = surface.samples[0].weight;
    EXPECT_GT(weight, 0.0);
    for (const auto& s : surface.samples) {
        const Vec3 p_world =
            centre + Vec3(s.p_device_m[0], -s.p_device_m[1], 0.012 - s.p_device_m[2]);
        EXPECT_GT(s.p_device_m[2], 0.012 + 0.002);  // pad side: well below the bone axis
        EXPECT_NEAR(s.signed_distance_m, p_world.z() - table_z, 1e-12);
        EXPECT_NEAR(s.normal_device[0], 0.0, 1e-12);
        EXPECT_NEAR(s.normal_device[1], 0.0, 1e-12);
        EXPECT_NEAR(s.normal_device[2], -1.0, 1e-12);
        EXPECT_DOUBLE_EQ(s.weight, weight);
    }
    // The lowest pad sample is 1 mm above the table.
    double lowest = 1.0;
    for (const auto& s : surface.samples) {
        lowest = std::min(lowest, s.signed_distance_m);
    }
    EXPECT_NEAR(lowest, 0.001, 1e-9);
    surface.header.source_id.assign("thimble");
    EXPECT_EQ(daemon::validate(surface, "thimble"), daemon::InputRejection::kNone);
}

// A pitched fingertip whose pad reaches 2 mm into a table. Placed there without a step, the
// sim presses the pad nowhere (no contact force yet): no sample is in contact, however deep
// the rigid pad points lie. After one step with the bone held the pad is pressed: each sample
// reports at least the rigid point's depth (deeper where its pressed skin is), along the
// table's normal.
TEST_F(TactileOutputTest, PitchedFingertipPressingTableReportsPenetrationAndTiltedNormal) {
    model.simulation.addCollider({HalfSpace{}, Vec3(0, 0, table_z + 0.003), Mat3::Identity(), 0.5});
    const TactileOutput output(model, config::Finger::kIndex, finger_from_device, material);
    const int body = model.bones.front().body;
    const double pitch = 0.3;
    const Mat3 rotation = Eigen::AngleAxisd(pitch, Vec3::UnitY()).toRotationMatrix();
    // The whole fingertip pitched, undeformed: its tissue turns with the bone.
    const Vec3 centre = model.simulation.bodyPosition(body);
    model.simulation.setBodyPose(body, centre, rotation);
    for (int node = 0; node < model.simulation.nodeCount(); ++node) {
        model.simulation.setNodePosition(
            node, centre + rotation * (model.simulation.nodePosition(node) - centre));
    }
    msgs::ContactSurface surface;
    output.fill(model.simulation, simulatedBone(model), surface);
    ASSERT_FALSE(surface.samples.empty());
    for (const auto& s : surface.samples) {
        EXPECT_GE(s.signed_distance_m, 0.0) << "in contact on a pad the sim presses nowhere";
    }

    model.simulation.setTrackingTarget(body, centre, rotation);
    (void)model.simulation.step(0.001);
    output.fill(model.simulation, simulatedBone(model), surface);
    ASSERT_FALSE(surface.samples.empty());
    double deepest = 1.0;
    const BonePose device = output.deviceFrame(simulatedBone(model));
    // The table's normal in D: (-sin, 0, -cos) of the pitch, less the little the contact
    // turned the bone in the step.
    const Vec3 up = device.rotation.transpose() * Vec3::UnitZ();
    EXPECT_LT(up[0], -0.2);
    EXPECT_NEAR(up[0], -std::sin(pitch), 0.06);
    for (const auto& s : surface.samples) {
        for (int i = 0; i < 3; ++i) {
            EXPECT_NEAR(s.normal_device[static_cast<std::size_t>(i)], up[i], 1e-12);
        }
        const Vec3 p_world =
            device.position_m +
            device.rotation * Vec3(s.p_device_m[0], s.p_device_m[1], s.p_device_m[2]);
        EXPECT_LE(s.signed_distance_m, p_world.z() - (table_z + 0.003) + 1e-12);
        deepest = std::min(deepest, s.signed_distance_m);
    }
    EXPECT_LT(deepest, -0.001);  // the pad reaches about 2 mm into the raised table
}

// The skin bulging past its rest shape presses before the rigid pad does: a sample whose skin
// node is inside the object and pushed on by the contact takes the skin's depth (the plate
// presses), one whose skin is clear keeps the rigid point's distance. Skin inside the object
// that no contact pushes on (the reference says 0 N) does not bring the plate up.
TEST_F(TactileOutputTest, WhereTheSkinPressesBeforeTheRigidPadTheSampleTakesTheSkinsDepth) {
    const int table =
        model.simulation.addCollider({HalfSpace{}, Vec3(0, 0, table_z), Mat3::Identity(), 0.5});
    const TactileOutput output(model, config::Finger::kIndex, finger_from_device, material);
    constexpr double kBulge = 0.0015;  // the skin 1.5 mm below its rest place, the bone still
    for (int node : model.simulation.skinNodes()) {
        model.simulation.setNodePosition(node,
                                         model.simulation.nodePosition(node) - Vec3(0, 0, kBulge));
    }
    const auto rigidDistance = [&](const msgs::ContactSample& s) {
        const BonePose device = output.deviceFrame(simulatedBone(model));
        const Vec3 p_world =
            device.position_m +
            device.rotation * Vec3(s.p_device_m[0], s.p_device_m[1], s.p_device_m[2]);
        return p_world.z() - table_z;
    };
    // No step yet: no contact force anywhere, although the bulged skin is inside the table.
    ASSERT_TRUE(model.simulation.contactForces().empty());
    msgs::ContactSurface surface;
    output.fill(model.simulation, simulatedBone(model), surface);
    ASSERT_FALSE(surface.samples.empty());
    for (const auto& s : surface.samples) {
        ASSERT_GT(rigidDistance(s), 0.0) << "the rigid pad is 1 mm or more above the table";
        EXPECT_NEAR(s.signed_distance_m, rigidDistance(s), 1e-12);
    }
    EXPECT_EQ(surface.reference_force_device_n[2], 0.0);

    // One step with the bone held: the contact pushes the bulged skin back out.
    const int bone = model.bones.front().body;
    model.simulation.setTrackingTarget(bone, model.simulation.bodyPosition(bone),
                                       model.simulation.bodyRotation(bone));
    (void)model.simulation.step(0.001);
    std::vector<double> pressed_depths;
    for (const auto& contact : model.simulation.contactForces()) {
        const double depth = model.simulation.nodePosition(contact.node).z() - table_z;
        if (contact.collider == table && contact.force_n.norm() > 1e-6 && depth < 0.0) {
            pressed_depths.push_back(depth);
        }
    }
    ASSERT_FALSE(pressed_depths.empty()) << "one step leaves pressed skin inside the table";
    output.fill(model.simulation, simulatedBone(model), surface);
    int touching = 0;
    int clear = 0;
    for (const auto& s : surface.samples) {
        const double rigid = rigidDistance(s);
        ASSERT_GT(rigid, 0.0);
        if (std::abs(s.signed_distance_m - rigid) < 1e-12) {
            ++clear;
            continue;
        }
        ++touching;
        EXPECT_TRUE(
            std::any_of(pressed_depths.begin(), pressed_depths.end(),
                        [&](double d) { return std::abs(d - s.signed_distance_m) < 1e-12; }))
            << s.signed_distance_m << " is neither the rigid point's nor a pressed skin node's";
        // The table's normal, world +z, seen in the device frame (the step tilted the bone a
        // little).
        const Vec3 up =
            output.deviceFrame(simulatedBone(model)).rotation.transpose() * Vec3::UnitZ();
        for (int i = 0; i < 3; ++i) {
            EXPECT_NEAR(s.normal_device[static_cast<std::size_t>(i)], up[i], 1e-12);
        }
    }
    std::printf(
        "after one step: %d samples at a pressed skin node's depth, %d at the rigid pad's\n",
        touching, clear);
    EXPECT_GT(touching, 0);
    EXPECT_GT(clear, 0);
    EXPECT_GT(std::hypot(surface.reference_force_device_n[0], surface.reference_force_device_n[1],
                         surface.reference_force_device_n[2]),
              0.0);
}

// The thimble's reference is the contact on its pad, the skin its plate can press: a
// fingertip that meets a wall tip-first has contact, but none the thimble can render; pressed
// on a table, the pad's reference carries the contact force.
TEST_F(TactileOutputTest, TheReferenceCountsTheContactOnThePadOnly) {
    const auto contactAfterSettling = [&](HandModel& hand, const ColliderDesc& object) {
        const int collider = hand.simulation.addCollider(object);
        const int bone = hand.bones.front().body;
        hand.simulation.setTrackingTarget(bone, hand.simulation.bodyPosition(bone),
                                          hand.simulation.bodyRotation(bone));
        for (int i = 0; i < 20; ++i) {
            (void)hand.simulation.step(0.005);
        }
        const TactileOutput output(hand, config::Finger::kIndex, finger_from_device, material);
        msgs::ContactSurface surface;
        output.fill(hand.simulation, simulatedBone(hand), surface);
        const auto& f = surface.reference_force_device_n;
        return std::pair{hand.simulation.forceOnCollider(collider).norm(),
                         std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2])};
    };
    // A wall across the tip, 1 mm into it (its normal -x: HalfSpace's +z turned about y).
    HandModel tip_first = buildHand(handConfig(config::HandModel::kFingertip), SolverSettings{});
    double tip_x = -1.0;
    for (int node : tip_first.simulation.skinNodes()) {
        tip_x = std::max(tip_x, tip_first.simulation.nodePosition(node).x());
    }
    const Mat3 facing_back = Eigen::AngleAxisd(-0.5 * std::numbers::pi, Vec3::UnitY()).matrix();
    const auto [wall_n, wall_pad_n] = contactAfterSettling(
        tip_first, {HalfSpace{}, Vec3(tip_x - 0.001, 0.0, 0.0), facing_back, 0.5});
    // The pad 1 mm into a table below it.
    const auto [table_n, table_pad_n] = contactAfterSettling(
        model, {HalfSpace{}, Vec3(0, 0, table_z + 0.002), Mat3::Identity(), 0.5});
    std::printf("tip-first: object %.3f N, pad reference %.3f N; pad on a table: %.3f N, %.3f N\n",
                wall_n, wall_pad_n, table_n, table_pad_n);
    ASSERT_GT(wall_n, 0.05) << "the tip does not touch the wall";
    // The lower quarter of the tip sphere is pad (its lowest samples touch the wall too).
    EXPECT_LT(wall_pad_n, 0.3 * wall_n) << "a tip-first contact counted as the pad's";
    ASSERT_GT(table_n, 0.05) << "the pad does not touch the table";
    EXPECT_NEAR(table_pad_n, table_n, 0.2 * table_n) << "the pad's contact left out";
}

// Where the FEM presses a sample's node harder than the linear pad would, the sample weighs the
// contact's secant stiffness (its normal force over the depth sent); no weight is below the
// linear pad's area weight, which hapticd's pad force limits rely on. So the pad model (the
// sum of weight times depth over the samples in contact) never gives less than the sim's pad
// force at the depths sent, on the simulated finger and on a tracked one 1.5 mm deeper alike
// (where the sim's force over the deeper depth is the softer secant, the area weight stays).
TEST_F(TactileOutputTest, NoSampleWeighsLessThanTheLinearPadAndThePadModelCoversTheSimsForce) {
    const double table_top = table_z + 0.002;  // the pad 1 mm into it
    const int table =
        model.simulation.addCollider({HalfSpace{}, Vec3(0, 0, table_top), Mat3::Identity(), 0.5});
    // Built on the rest pad, as handsim builds it (the pad's radius is measured then).
    const TactileOutput output(model, config::Finger::kIndex, finger_from_device, material);
    const int bone = model.bones.front().body;
    model.simulation.setTrackingTarget(bone, model.simulation.bodyPosition(bone),
                                       model.simulation.bodyRotation(bone));
    for (int i = 0; i < 20; ++i) {
        (void)model.simulation.step(0.005);
    }
    msgs::ContactSurface clear_of_it;
    {
        HandModel untouched =
            buildHand(handConfig(config::HandModel::kFingertip), SolverSettings{});
        const TactileOutput far(untouched, config::Finger::kIndex, finger_from_device, material);
        far.fill(untouched.simulation, simulatedBone(untouched), clear_of_it);
    }
    const double area_weight = clear_of_it.samples[0].weight;
    const BonePose simulated = simulatedBone(model);
    const BonePose tracked{simulated.position_m - Vec3(0, 0, 0.0015), simulated.rotation};
    for (const BonePose& finger : {simulated, tracked}) {
        msgs::ContactSurface surface;
        output.fill(model.simulation, finger, surface);
        double model_force = 0.0;
        int secant = 0;
        for (const auto& s : surface.samples) {
            EXPECT_GE(s.weight, area_weight);
            if (s.signed_distance_m < 0.0) {
                model_force += s.weight * -s.signed_distance_m;
                secant += s.weight > area_weight ? 1 : 0;
            } else {
                EXPECT_DOUBLE_EQ(s.weight, area_weight);
            }
        }
        // The normal force of the contacts on the pad: the table's normal is +z.
        const double pad_force = -surface.reference_force_device_n[2];
        std::printf(
            "%d samples weigh their secant; pad model %.4f N, the sim's pad %.4f N "
            "(table %.4f N)\n",
            secant, model_force, pad_force, model.simulation.forceOnCollider(table).norm());
        // This light press (0.23 N) is softer than the linear pad everywhere; the secant wins
        // on firmer contacts (FemErrorAnalysis.TheOptimiserMatchesAFlatContact...: the edge).
        EXPECT_GE(model_force, pad_force * (1.0 - 1e-9));
    }
}

// The device is strapped to the user's finger: where the tracked finger is 1.5 mm deeper than
// the simulated one the contact holds back, every pad sample lies 1.5 mm deeper against the
// object (the plate presses 1.5 mm further), while the reference, the sim's contact on its
// pad, is the same force and moment about the device.
TEST_F(TactileOutputTest, TheSamplesLieOnTheTrackedFingerNotOnTheSimulatedOne) {
    const double table_top = table_z + 0.002;  // the pad 1 mm into it
    model.simulation.addCollider({HalfSpace{}, Vec3(0, 0, table_top), Mat3::Identity(), 0.5});
    const int bone = model.bones.front().body;
    model.simulation.setTrackingTarget(bone, model.simulation.bodyPosition(bone),
                                       model.simulation.bodyRotation(bone));
    for (int i = 0; i < 20; ++i) {
        (void)model.simulation.step(0.005);
    }
    const TactileOutput output(model, config::Finger::kIndex, finger_from_device, material);
    EXPECT_EQ(output.bone(), 0U);
    const BonePose simulated = simulatedBone(model);
    constexpr double kDeeper = 0.0015;
    const BonePose tracked{simulated.position_m - Vec3(0, 0, kDeeper), simulated.rotation};
    msgs::ContactSurface on_simulated;
    msgs::ContactSurface on_tracked;
    output.fill(model.simulation, simulated, on_simulated);
    output.fill(model.simulation, tracked, on_tracked);
    ASSERT_EQ(on_simulated.samples.size(), on_tracked.samples.size());
    // The table pushes the pad towards the nail: device -z.
    ASSERT_LT(on_simulated.reference_force_device_n[2], -0.05) << "the sim presses its pad";
    const BonePose device = output.deviceFrame(tracked);
    EXPECT_NEAR((device.position_m - output.deviceFrame(simulated).position_m).z(), -kDeeper,
                1e-15);
    double deepest_simulated = 1.0;
    double deepest_tracked = 1.0;
    double deepest_rigid = 1.0;
    for (std::size_t i = 0; i < on_tracked.samples.size(); ++i) {
        const auto& s = on_tracked.samples[i];
        for (std::size_t k = 0; k < 3; ++k) {
            EXPECT_NEAR(s.p_device_m[k], on_simulated.samples[i].p_device_m[k], 1e-12)
                << "the pad is rigid with the device";
        }
        const Vec3 p_world =
            device.position_m +
            device.rotation * Vec3(s.p_device_m[0], s.p_device_m[1], s.p_device_m[2]);
        const double rigid = p_world.z() - table_top;
        EXPECT_LE(s.signed_distance_m, rigid + 1e-12);
        deepest_rigid = std::min(deepest_rigid, rigid);
        deepest_tracked = std::min(deepest_tracked, s.signed_distance_m);
        deepest_simulated = std::min(deepest_simulated, on_simulated.samples[i].signed_distance_m);
    }
    std::printf("deepest pad sample: %.3f mm on the simulated finger, %.3f mm on the tracked\n",
                deepest_simulated * 1e3, deepest_tracked * 1e3);
    EXPECT_NEAR(deepest_tracked, deepest_rigid, 1e-12);
    EXPECT_LE(deepest_tracked, deepest_simulated - kDeeper + 1e-9);
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_NEAR(on_tracked.reference_force_device_n[k],
                    on_simulated.reference_force_device_n[k], 1e-12);
        EXPECT_NEAR(on_tracked.reference_moment_device_nm[k],
                    on_simulated.reference_moment_device_nm[k], 1e-12);
    }
    // Turned as well (8 degrees about the phalanx's axis and 5 about its side): the contact is
    // carried rigidly onto the tracked pad, so in each finger's device frame the reference is
    // the same force and moment.
    const Mat3 turn =
        (Eigen::AngleAxisd(0.14, Vec3::UnitX()) * Eigen::AngleAxisd(0.09, Vec3::UnitY()))
            .toRotationMatrix();
    const BonePose turned{tracked.position_m, turn * simulated.rotation};
    msgs::ContactSurface on_turned;
    output.fill(model.simulation, turned, on_turned);
    ASSERT_GT(std::abs(on_simulated.reference_moment_device_nm[0]) +
                  std::abs(on_simulated.reference_moment_device_nm[1]),
              1e-6)
        << "a moment to compare";
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_NEAR(on_turned.reference_force_device_n[k], on_simulated.reference_force_device_n[k],
                    1e-12);
        EXPECT_NEAR(on_turned.reference_moment_device_nm[k],
                    on_simulated.reference_moment_device_nm[k], 1e-12);
    }
}

}  // namespace
}  // namespace haptic::softhand
