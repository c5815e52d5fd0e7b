// Procedural hand builder and elastic tracking through the intermediate skeleton.

#include "haptic/softhand/hand_builder.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "haptic/softhand/elastic_tracking.hpp"

namespace haptic::softhand {
namespace {

config::HandConfig handConfig(config::HandModel model, int resolution) {
    config::HandConfig hand;
    hand.model = model;
    hand.finger = model == config::HandModel::kHand
                      ? std::nullopt
                      : std::optional<config::Finger>(config::Finger::kIndex);
    hand.resolution = resolution;
    hand.anthropometry = {0.19, 0.085, 0.016};
    return hand;
}

std::vector<BonePose> buildPoses(const HandModel& model) {
    std::vector<BonePose> poses;
    for (const auto& bone : model.bones) {
        poses.push_back(
            {model.simulation.bodyPosition(bone.body), model.simulation.bodyRotation(bone.body)});
    }
    return poses;
}

TEST(SofthandHandBuilder, FingertipSceneBuildsOnlyTheDistalPhalanx) {
    const HandModel coarse = buildHand(handConfig(config::HandModel::kFingertip, 1), {});
    const HandModel fine = buildHand(handConfig(config::HandModel::kFingertip, 3), {});
    ASSERT_EQ(coarse.bones.size(), 1u);
    EXPECT_EQ(coarse.bones.front().name, "index_distal");
    EXPECT_EQ(coarse.palm_body, -1);
    EXPECT_TRUE(coarse.joints.empty());
    EXPECT_NEAR(coarse.bones.front().length_m, 0.095 * 0.19, 1e-12);
    EXPECT_LT(coarse.simulation.nodeCount(), fine.simulation.nodeCount());
    EXPECT_LT(coarse.simulation.tetCount(), fine.simulation.tetCount());
    EXPECT_FALSE(coarse.simulation.skinNodes().empty());
    // The pad reaches one fingertip radius below the bone axis.
    double lowest = 0.0;
    for (int i = 0; i < coarse.simulation.nodeCount(); ++i) {
        lowest = std::min(lowest, coarse.simulation.nodePosition(i).z());
    }
    EXPECT_NEAR(lowest, -0.008, 0.002);
}

// hand.anthropometry.hand_length_m sets the phalanges' lengths in proportion, and
// fingertip_diameter_m the pad's reach below the bone.
TEST(SofthandHandBuilder, TheHandsLengthAndFingertipDiameterSizeTheFinger) {
    const auto lowestNode = [](const HandModel& model) {
        double lowest = 0.0;
        for (int i = 0; i < model.simulation.nodeCount(); ++i) {
            lowest = std::min(lowest, model.simulation.nodePosition(i).z());
        }
        return lowest;
    };
    const config::HandConfig shipped = handConfig(config::HandModel::kFingertip, 1);
    config::HandConfig longer = shipped;
    longer.anthropometry.hand_length_m = 0.21;
    config::HandConfig wider = shipped;
    wider.anthropometry.fingertip_diameter_m = 0.020;
    const HandModel shipped_model = buildHand(shipped, {});
    const HandModel longer_model = buildHand(longer, {});
    const HandModel wider_model = buildHand(wider, {});
    EXPECT_NEAR(longer_model.bones.front().length_m / shipped_model.bones.front().length_m,
                0.21 / 0.19, 1e-12);
    EXPECT_NEAR(lowestNode(wider_model) / lowestNode(shipped_model), 0.020 / 0.016, 0.02);
    EXPECT_NEAR(lowestNode(longer_model), lowestNode(shipped_model), 1e-4)
        << "the length does not change the pad's reach";
}

TEST(SofthandHandBuilder, FingerSceneHasThreeJointedPhalangesOnAKinematicPalm) {
    const HandModel model = buildHand(handConfig(config::HandModel::kFinger, 1), {});
    ASSERT_EQ(model.bones.size(), 4u);
    EXPECT_EQ(model.joints.size(), 3u);
    ASSERT_GE(model.palm_body, 0);
    EXPECT_TRUE(model.simulation.body(model.palm_body).kinematic);
    EXPECT_NE(model.findBone("index_proximal"), nullptr);
    EXPECT_NE(model.findBone("index_middle"), nullptr);
    EXPECT_NE(model.findBone("index_distal"), nullptr);
    EXPECT_EQ(model.findBone("thumb_distal"), nullptr);
}

// hand.finger names the finger a fingertip or one-finger scene builds: the middle finger's
// bones, at its own lengths (longer than the index's), and no index.
TEST(SofthandHandBuilder, TheFingerKeyChoosesTheFingerBuilt) {
    const double hand_length = 0.19;
    for (const auto model : {config::HandModel::kFingertip, config::HandModel::kFinger}) {
        config::HandConfig middle = handConfig(model, 1);
        middle.finger = config::Finger::kMiddle;
        const HandModel built = buildHand(middle, {});
        const auto* distal = built.findBone("middle_distal");
        ASSERT_NE(distal, nullptr);
        EXPECT_EQ(built.findBone("index_distal"), nullptr);
        const auto middle_lengths = phalanxLengths(config::Finger::kMiddle, hand_length);
        const auto index_lengths = phalanxLengths(config::Finger::kIndex, hand_length);
        EXPECT_NEAR(distal->length_m, middle_lengths[2], 1e-12);
        if (model == config::HandModel::kFinger) {
            ASSERT_NE(built.findBone("middle_proximal"), nullptr);
            EXPECT_NEAR(built.findBone("middle_proximal")->length_m, middle_lengths[0], 1e-12);
            EXPECT_GT(middle_lengths[0], index_lengths[0]) << "the two fingers would not differ";
        }
    }
}

// Level 0 (two cells across a finger) is the whole hand's real-time level, level 1 the next.
TEST(SofthandHandBuilder, WholeHandHasSixteenBonesAndStaysTogetherUnderGravity) {
    for (const int level : {0, 1}) {
        SCOPED_TRACE("resolution " + std::to_string(level));
        HandModel model = buildHand(handConfig(config::HandModel::kHand, level), {});
        EXPECT_EQ(model.bones.size(), 16u);
        EXPECT_EQ(model.joints.size(), 15u);
        ElasticTracking tracking(model);
        const auto poses = buildPoses(model);
        ASSERT_TRUE(tracking.setTrackedPoses(poses, nullptr));
        for (int s = 0; s < 4; ++s) {
            tracking.update(model, 0.01);
            const StepReport report = model.simulation.step(0.01);
            ASSERT_TRUE(std::isfinite(report.energy_j));
        }
        // Tracked in its build pose, every bone stays within a few millimetres of it.
        for (std::size_t k = 0; k < model.bones.size(); ++k) {
            EXPECT_LT(
                (model.simulation.bodyPosition(model.bones[k].body) - poses[k].position_m).norm(),
                0.005)
                << model.bones[k].name;
        }
    }
}

// hand.anthropometry.hand_breadth_m spreads the fingers across the palm: the index and the
// little finger's proximal phalanges sit that much further apart, in proportion.
TEST(SofthandHandBuilder, TheHandsBreadthSpreadsTheFingers) {
    const auto spread = [](double breadth_m) {
        config::HandConfig hand = handConfig(config::HandModel::kHand, 0);
        hand.anthropometry.hand_breadth_m = breadth_m;
        const HandModel model = buildHand(hand, {});
        Vec3 index = Vec3::Zero();
        Vec3 little = Vec3::Zero();
        for (const auto& bone : model.bones) {
            if (bone.name == "index_proximal") {
                index = bone.rest_position_m;
            } else if (bone.name == "little_proximal") {
                little = bone.rest_position_m;
            }
        }
        return std::abs(index.y() - little.y());
    };
    const double shipped = spread(0.085);
    ASSERT_GT(shipped, 0.02);
    EXPECT_NEAR(spread(0.1) / shipped, 0.1 / 0.085, 1e-6);
}

TEST(SofthandHandBuilder, ResolutionOutsideZeroToEightIsRefused) {
    EXPECT_THROW((void)buildHand(handConfig(config::HandModel::kFingertip, -1), {}),
                 std::invalid_argument);
    EXPECT_THROW((void)buildHand(handConfig(config::HandModel::kFingertip, 9), {}),
                 std::invalid_argument);
    EXPECT_EQ(cellsAcross(0), 2);
    EXPECT_EQ(cellsAcross(1), 4);
}

TEST(SofthandElasticTracking, IntermediateSkeletonRepairsAJointBreakingInput) {
    HandModel model = buildHand(handConfig(config::HandModel::kFinger, 1), {});
    ElasticTracking tracking(model);
    auto poses = buildPoses(model);
    const BoneInfo& middle = *model.findBone("index_middle");
    const BoneInfo& distal = *model.findBone("index_distal");
    const std::size_t distal_index = static_cast<std::size_t>(&distal - model.bones.data());
    // The tracker reports the distal phalanx 1 cm to the side: the DIP joint is torn open.
    poses[distal_index].position_m += Vec3(0.0, 0.01, 0.0);
    ASSERT_TRUE(tracking.setTrackedPoses(poses, nullptr));
    tracking.update(model, 0.01);
    const std::size_t middle_index = static_cast<std::size_t>(&middle - model.bones.data());
    const auto middle_target = tracking.intermediatePose(static_cast<int>(middle_index));
    const auto distal_target = tracking.intermediatePose(static_cast<int>(distal_index));
    const Vec3 middle_dip_end =
        middle_target.position_m + middle_target.rotation * Vec3(0.5 * middle.length_m, 0, 0);
    const Vec3 distal_dip_end =
        distal_target.position_m + distal_target.rotation * Vec3(-0.5 * distal.length_m, 0.0, 0.0);
    // The targets handed to the simulation keep the joint far better than the raw input
    // (whose DIP gap is 1 cm): the joint energy spreads the error over the chain.
    EXPECT_LT((distal_dip_end - middle_dip_end).norm(), 0.3 * 0.01);
}

TEST(SofthandElasticTracking, BlockedFingertipLagsInsteadOfTearingThrough) {
    SolverSettings settings;
    settings.contact_stiffness_n_per_m = 5000.0;
    HandModel model = buildHand(handConfig(config::HandModel::kFingertip, 1), settings);
    const double table_z = -0.0085;
    model.simulation.addCollider({HalfSpace{}, Vec3(0.0, 0.0, table_z), Mat3::Identity(), 0.8});
    ElasticTracking tracking(model);
    auto poses = buildPoses(model);
    poses[0].position_m.z() -= 0.02;  // the tracked finger is 2 cm inside the table
    ASSERT_TRUE(tracking.setTrackedPoses(poses, nullptr));
    for (int s = 0; s < 60; ++s) {
        tracking.update(model, 0.01);
        ASSERT_TRUE(std::isfinite(model.simulation.step(0.01).energy_j));
    }
    // The bone stays above the table, cushioned by the pad; the tissue is not torn off.
    EXPECT_GT(model.simulation.bodyPosition(model.bones[0].body).z(), table_z);
    for (int i = 0; i < model.simulation.nodeCount(); ++i) {
        EXPECT_GT(model.simulation.nodePosition(i).z(), table_z - 0.002);
    }
}

TEST(SofthandElasticTracking, NonFiniteTrackedPoseIsRefusedWithAReason) {
    HandModel model = buildHand(handConfig(config::HandModel::kFinger, 1), {});
    ElasticTracking tracking(model);
    auto poses = buildPoses(model);
    poses[2].position_m.x() = std::numeric_limits<double>::quiet_NaN();
    std::string reason;
    EXPECT_FALSE(tracking.setTrackedPoses(poses, &reason));
    EXPECT_THAT(reason, ::testing::HasSubstr("bone 2"));
    EXPECT_FALSE(tracking.setTrackedPoses(std::vector<BonePose>(2), &reason));
    EXPECT_THAT(reason, ::testing::HasSubstr("count"));
    EXPECT_TRUE(tracking.trackedPoses()[2].position_m.allFinite());
}

}  // namespace
}  // namespace haptic::softhand
