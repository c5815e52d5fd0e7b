#include "finger_flex_scene.hpp"

#include <cmath>

namespace haptic::softhand::bench {

FingerFlex::FingerFlex(int level, int pcg_cap, double pcg_tolerance)
    : model_(buildHand(handConfig(config::HandModel::kFinger, level),
                       solverSettings(pcg_cap, pcg_tolerance))),
      tracking_(model_) {
    table_ =
        model_.simulation.addCollider({HalfSpace{}, Vec3(0.0, 0.0, -0.03), Mat3::Identity(), 0.6});
    for (const auto& bone : model_.bones) {
        build_.push_back(
            {model_.simulation.bodyPosition(bone.body), model_.simulation.bodyRotation(bone.body)});
    }
    poses_ = build_;
}

void FingerFlex::setInput(int step) {
    const double t = (step % kCycleSteps) * kDt;
    const double angle = 0.8 * std::sin(3.14159265 * t);
    Vec3 joint = build_[0].position_m + Vec3(0.5 * 0.45 * 0.19, 0.0, 0.0);
    Mat3 rotation = Mat3::Identity();
    for (std::size_t k = 1; k < poses_.size(); ++k) {
        rotation = rotation * Eigen::AngleAxisd(angle / 3.0, Vec3::UnitY()).toRotationMatrix();
        const double length = model_.bones[k].length_m;
        poses_[k] = {joint + rotation * Vec3(0.5 * length, 0.0, 0.0), rotation};
        joint += rotation * Vec3(length, 0.0, 0.0);
    }
    tracking_.setTrackedPoses(poses_, nullptr);
}

StepReport FingerFlex::stepBy(double dt_s) {
    tracking_.update(model_, dt_s);
    return model_.simulation.step(dt_s);
}

Sample FingerFlex::sample() const {
    return {model_.simulation.forceOnCollider(table_).z(),
            model_.simulation.bodyPosition(distalBody())};
}

}  // namespace haptic::softhand::bench
