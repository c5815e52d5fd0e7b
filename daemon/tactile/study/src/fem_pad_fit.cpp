#include "haptic/tactile/fem_pad_fit.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace haptic::tactile {

namespace {

// How far below the pad (along +z in D) the plate sits for the press that touches nothing:
// its surface carries the linear pad's area weights, not a contact's.
constexpr double kClearOfThePadM = 0.01;
// The scan's range is optimiser.pad_stiffening_depth_m's: at 0.1 m the law stiffens by 2 % at
// the thimble's deepest 4 mm, i.e. it is linear.
constexpr double kMinDepthM = 1e-4;
constexpr double kMaxDepthM = 0.1;
constexpr int kScanPoints = 61;
constexpr int kGoldenSteps = 60;

struct PadSample {
    double height_m;  // along z in D: the pad's lowest point is the largest
    double weight;    // linear pad: area x stiffness per area (N/m)
};

// The samples under the FEM's plate, a square of 2 plate radii centred under the pad's lowest
// point (FemFingertip::pressPlate): the pad's contact line is longer than the plate, and a
// sample beyond it is pressed by nothing.
std::vector<PadSample> underThePlate(const msgs::ContactSurface& surface,
                                     const Eigen::Vector3d& pad_point, double plate_radius_m) {
    std::vector<PadSample> samples;
    for (const msgs::ContactSample& sample : surface.samples) {
        if (std::abs(sample.p_device_m[0] - pad_point.x()) <= plate_radius_m &&
            std::abs(sample.p_device_m[1] - pad_point.y()) <= plate_radius_m) {
            samples.push_back({sample.p_device_m[2], sample.weight});
        }
    }
    return samples;
}

// sum_i w_i s (exp(delta_i / s) - 1) for the flat plate `depth_m` past the lowest point.
double lawForce(const std::vector<PadSample>& samples, double lowest_m, double depth_m,
                double stiffening_depth_m) {
    double force = 0.0;
    for (const PadSample& sample : samples) {
        const double indentation = depth_m - (lowest_m - sample.height_m);
        if (indentation > 0.0) {
            force +=
                sample.weight * stiffening_depth_m * std::expm1(indentation / stiffening_depth_m);
        }
    }
    return force;
}

struct ScaleFit {
    double scale;
    double sum_squared_relative;
};

// The scale minimising sum ((c m_k - f_k) / f_k)^2, in closed form.
ScaleFit fitScale(const std::vector<double>& model, const std::vector<double>& fem) {
    double mm = 0.0;
    double mf = 0.0;
    for (std::size_t k = 0; k < fem.size(); ++k) {
        const double m = model[k] / fem[k];
        mm += m * m;
        mf += m;
    }
    const double scale = mm > 0.0 ? mf / mm : 0.0;
    double sum = 0.0;
    for (std::size_t k = 0; k < fem.size(); ++k) {
        const double r = (scale * model[k] - fem[k]) / fem[k];
        sum += r * r;
    }
    return {scale, sum};
}

}  // namespace

std::vector<double> defaultPadFitDepths() {
    return {0.00025, 0.0005, 0.00075, 0.001, 0.00125, 0.0015, 0.00175, 0.002};
}

PadLawFit fitPadLawToFem(const FemFingertip& finger, double plate_radius_m,
                         const std::vector<double>& depths_m) {
    PlatformPose clear;
    clear.position_m = finger.padPoint() + Eigen::Vector3d(0.0, 0.0, kClearOfThePadM);
    const FemPress untouched = finger.pressPlate(clear, plate_radius_m);
    const std::vector<PadSample> samples =
        underThePlate(untouched.surface, finger.padPoint(), plate_radius_m);
    const double lowest = finger.padPoint().z();

    std::vector<double> fem;
    for (const double depth : depths_m) {
        PlatformPose flat;
        flat.position_m = finger.padPoint() - Eigen::Vector3d(0.0, 0.0, depth);
        const double force = finger.pressPlate(flat, plate_radius_m).contact.force_on_finger_n.z();
        // The finger is pushed towards its nail, -z in D.
        if (!(-force > 0.0)) {
            throw std::runtime_error("pad fit: the plate " + std::to_string(depth * 1e3) +
                                     " mm into the pad presses nothing");
        }
        fem.push_back(-force);
    }
    const auto modelAt = [&](double s) {
        std::vector<double> model;
        for (const double depth : depths_m) {
            model.push_back(lawForce(samples, lowest, depth, s));
        }
        return model;
    };
    const auto cost = [&](double s) { return fitScale(modelAt(s), fem).sum_squared_relative; };

    // Scan log-spaced, then refine by golden section around the best point.
    const double log_min = std::log(kMinDepthM);
    const double log_step = (std::log(kMaxDepthM) - log_min) / (kScanPoints - 1);
    int best = 0;
    double best_cost = cost(kMinDepthM);
    for (int k = 1; k < kScanPoints; ++k) {
        const double c = cost(std::exp(log_min + k * log_step));
        if (c < best_cost) {
            best_cost = c;
            best = k;
        }
    }
    double lo = log_min + std::max(best - 1, 0) * log_step;
    double hi = log_min + std::min(best + 1, kScanPoints - 1) * log_step;
    const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int k = 0; k < kGoldenSteps; ++k) {
        const double a = hi - ratio * (hi - lo);
        const double b = lo + ratio * (hi - lo);
        if (cost(std::exp(a)) < cost(std::exp(b))) {
            hi = b;
        } else {
            lo = a;
        }
    }
    PadLawFit fit;
    fit.stiffening_depth_m = std::min(std::exp(0.5 * (lo + hi)), kMaxDepthM);
    fit.linear = fit.stiffening_depth_m > 0.99 * kMaxDepthM;
    const std::vector<double> model = modelAt(fit.stiffening_depth_m);
    fit.weight_scale = fitScale(model, fem).scale;
    double sum = 0.0;
    for (std::size_t k = 0; k < fem.size(); ++k) {
        const double predicted = fit.weight_scale * model[k];
        const double relative = std::abs(predicted - fem[k]) / fem[k];
        sum += relative * relative;
        fit.max_relative_error = std::max(fit.max_relative_error, relative);
        fit.points.push_back({depths_m[k], fem[k], predicted});
    }
    fit.rms_relative_error = std::sqrt(sum / static_cast<double>(fem.size()));
    return fit;
}

}  // namespace haptic::tactile
