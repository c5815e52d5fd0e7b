#include "haptic/tactile/fingertip_model.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace haptic::tactile {

HalfSpaceObstacle::HalfSpaceObstacle(const Eigen::Vector3d& point_m,
                                     const Eigen::Vector3d& outward_normal)
    : point_m_(point_m), normal_(outward_normal.normalized()) {}

double HalfSpaceObstacle::signedDistance(const Eigen::Vector3d& point_m,
                                         Eigen::Vector3d& normal) const {
    normal = normal_;
    return normal_.dot(point_m - point_m_);
}

SphereObstacle::SphereObstacle(const Eigen::Vector3d& centre_m, double radius_m)
    : centre_m_(centre_m), radius_m_(radius_m) {}

double SphereObstacle::signedDistance(const Eigen::Vector3d& point_m,
                                      Eigen::Vector3d& normal) const {
    const Eigen::Vector3d rel = point_m - centre_m_;
    const double r = rel.norm();
    normal = r > 0.0 ? Eigen::Vector3d(rel / r) : Eigen::Vector3d(-Eigen::Vector3d::UnitZ());
    return r - radius_m_;
}

RightAngleEdgeObstacle::RightAngleEdgeObstacle(const Eigen::Vector3d& ridge_point_m,
                                               const Eigen::Vector3d& normal_a,
                                               const Eigen::Vector3d& normal_b)
    : ridge_point_m_(ridge_point_m),
      normal_a_(normal_a.normalized()),
      normal_b_(normal_b.normalized()) {
    if (std::fabs(normal_a_.dot(normal_b_)) > 1e-9) {
        throw std::invalid_argument("RightAngleEdgeObstacle: face normals must be perpendicular");
    }
}

double RightAngleEdgeObstacle::signedDistance(const Eigen::Vector3d& point_m,
                                              Eigen::Vector3d& normal) const {
    const Eigen::Vector3d rel = point_m - ridge_point_m_;
    const double da = normal_a_.dot(rel);
    const double db = normal_b_.dot(rel);
    if (da > 0.0 && db > 0.0) {
        // Nearest point on the ridge: with perpendicular faces the offsets are orthogonal.
        const double distance = std::hypot(da, db);
        normal = (da * normal_a_ + db * normal_b_) / distance;
        return distance;
    }
    normal = da >= db ? normal_a_ : normal_b_;
    return std::max(da, db);
}

PlateObstacle::PlateObstacle(const PlatformPose& pose, double plate_radius_m)
    : centre_m_(pose.position_m), normal_(pose.plateNormal()), radius_m_(plate_radius_m) {}

double PlateObstacle::signedDistance(const Eigen::Vector3d& point_m,
                                     Eigen::Vector3d& normal) const {
    normal = normal_;
    const Eigen::Vector3d rel = point_m - centre_m_;
    const double d = normal_.dot(rel);
    if ((rel - d * normal_).norm() > radius_m_) {
        return std::numeric_limits<double>::infinity();  // beside the disc: never pressed
    }
    return d;
}

NonlinearPadModel::NonlinearPadModel(const PadModelParameters& parameters)
    : parameters_(parameters) {
    const double s = parameters_.node_spacing_m;
    const int half = static_cast<int>(std::ceil(parameters_.footprint_radius_m / s));
    for (int ix = -half; ix <= half; ++ix) {
        for (int iy = -half; iy <= half; ++iy) {
            const double x = ix * s;
            const double y = iy * s;
            if (std::hypot(x, y) <= parameters_.footprint_radius_m) {
                nodes_m_.push_back(surfacePoint(x, y));
            }
        }
    }
    node_area_m2_ = s * s;
}

Eigen::Vector3d NonlinearPadModel::surfacePoint(double x_m, double y_m) const {
    const double R = parameters_.pad_radius_m;
    const double centre_z = parameters_.contact_height_m - R;
    return {x_m, y_m, centre_z + std::sqrt(R * R - x_m * x_m - y_m * y_m)};
}

double NonlinearPadModel::pressure(double depth_m) const {
    return depth_m <= 0.0 ? 0.0
                          : parameters_.pressure_scale_pa *
                                std::expm1(depth_m / parameters_.stiffening_depth_m);
}

double NonlinearPadModel::pressureSlope(double depth_m) const {
    return parameters_.pressure_scale_pa / parameters_.stiffening_depth_m *
           std::exp(std::max(depth_m, 0.0) / parameters_.stiffening_depth_m);
}

PadContact NonlinearPadModel::press(const Obstacle& obstacle) const {
    PadContact out;
    out.node_in_contact.assign(nodes_m_.size(), false);
    const double R = parameters_.pad_radius_m;
    for (std::size_t i = 0; i < nodes_m_.size(); ++i) {
        Eigen::Vector3d normal;
        const double distance = obstacle.signedDistance(nodes_m_[i], normal);
        if (distance < 0.0) {
            // Projected grid area divided by the cap's slope: the node's share of skin.
            const Eigen::Vector3d& p = nodes_m_[i];
            const double slope = R / std::sqrt(R * R - p.x() * p.x() - p.y() * p.y());
            out.force_on_finger_n += pressure(-distance) * node_area_m2_ * slope * normal;
            out.node_in_contact[i] = true;
            ++out.contact_count;
        }
    }
    return out;
}

msgs::ContactSurface NonlinearPadModel::contactSurface(const Obstacle& obstacle, int sample_count,
                                                       SampleWeighting weighting) const {
    // Sunflower (Fibonacci) samples: equal projected area each, no grid alignment.
    msgs::ContactSurface surface;
    const double R = parameters_.pad_radius_m;
    const double radius = parameters_.footprint_radius_m;
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    const double area = std::numbers::pi * radius * radius / sample_count;
    for (int k = 0; k < sample_count; ++k) {
        const double r = radius * std::sqrt((k + 0.5) / sample_count);
        const double x = r * std::cos(k * golden);
        const double y = r * std::sin(k * golden);
        const Eigen::Vector3d p = surfacePoint(x, y);
        Eigen::Vector3d normal;
        const double distance = obstacle.signedDistance(p, normal);
        msgs::ContactSample sample;
        sample.p_device_m = {p.x(), p.y(), p.z()};
        sample.signed_distance_m = distance;
        sample.normal_device = {normal.x(), normal.y(), normal.z()};
        sample.weight = area * R / std::sqrt(R * R - x * x - y * y);
        surface.samples.push_back(sample);
    }
    if (weighting == SampleWeighting::kContactStiffness) {
        for (msgs::ContactSample& s : surface.samples.used()) {
            s.weight *= pressureSlope(-s.signed_distance_m);
        }
    }
    if (weighting == SampleWeighting::kContactForce) {
        double contact_area = 0.0;
        double contact_force = 0.0;
        for (const msgs::ContactSample& s : surface.samples) {
            if (s.signed_distance_m < 0.0) {
                contact_area += s.weight;
                contact_force += s.weight * pressure(-s.signed_distance_m);
            }
        }
        for (msgs::ContactSample& s : surface.samples.used()) {
            if (s.signed_distance_m < 0.0 && contact_force > 0.0) {
                s.weight *= pressure(-s.signed_distance_m) * contact_area / contact_force;
            }
        }
    }
    return surface;
}

double NonlinearPadModel::flatPlateForce(double depth_m) const {
    const Eigen::Vector3d into_finger = -Eigen::Vector3d::UnitZ();
    const HalfSpaceObstacle plate(Eigen::Vector3d(0.0, 0.0, parameters_.contact_height_m - depth_m),
                                  into_finger);
    return press(plate).force_on_finger_n.norm();
}

}  // namespace haptic::tactile
