#pragma once

// Fingertip contact models for the error analysis (docs/algorithms.md §3.7): press the finger pad
// with an obstacle (a virtual object or the device plate) and read back the contact force and
// the set of pad nodes in contact.
//
// FingertipContactModel is the seam for the soft-tissue FEM of the soft-hand work: the FEM
// implements press() and replaces NonlinearPadModel without changing the analysis.
//
// NonlinearPadModel (a documented stand-in, [REC]): the undeformed pad is a spherical cap of
// radius pad_radius_m whose lowest point is at (0, 0, contact_height_m) in the device base
// frame, sampled by a dense grid of nodes. Each node is an independent nonlinear spring
// (a Winkler foundation) with the exponential stiffening measured on human fingertips:
//
//   pressure(delta) = pressure_scale_pa * (exp(delta / stiffening_depth_m) - 1)
//
// where delta >= 0 is how far the undeformed node lies inside the obstacle; the node force is
// pressure * node area along the obstacle's outward normal. With the defaults a flat plate
// pressed 2 mm into the pad gives ~1 N, 1 mm gives ~0.16 N. Limits: no lateral coupling
// between nodes (the contact area equals the geometric overlap), no friction, no bone. Not
// for the RT path (allocates at construction; press() is O(nodes)).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "haptic/msgs/messages.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::tactile {

// Rigid obstacle: signed distance (positive outside, i.e. on the finger side) and the outward
// unit normal at the nearest surface point.
class Obstacle {
  public:
    virtual ~Obstacle() = default;
    [[nodiscard]] virtual double signedDistance(const Eigen::Vector3d& point_m,
                                                Eigen::Vector3d& outward_normal) const = 0;
};

// Everything on the far side of a plane; `outward_normal` points towards the finger.
class HalfSpaceObstacle final : public Obstacle {
  public:
    HalfSpaceObstacle(const Eigen::Vector3d& point_m, const Eigen::Vector3d& outward_normal);
    double signedDistance(const Eigen::Vector3d& point_m, Eigen::Vector3d& normal) const override;

  private:
    Eigen::Vector3d point_m_;
    Eigen::Vector3d normal_;
};

class SphereObstacle final : public Obstacle {
  public:
    SphereObstacle(const Eigen::Vector3d& centre_m, double radius_m);
    double signedDistance(const Eigen::Vector3d& point_m, Eigen::Vector3d& normal) const override;

  private:
    Eigen::Vector3d centre_m_;
    double radius_m_;
};

// A 90-degree convex edge: the intersection of two half-spaces with perpendicular outward
// normals. Exact distance outside (to a face or to the ridge line).
class RightAngleEdgeObstacle final : public Obstacle {
  public:
    RightAngleEdgeObstacle(const Eigen::Vector3d& ridge_point_m, const Eigen::Vector3d& normal_a,
                           const Eigen::Vector3d& normal_b);
    double signedDistance(const Eigen::Vector3d& point_m, Eigen::Vector3d& normal) const override;

  private:
    Eigen::Vector3d ridge_point_m_;
    Eigen::Vector3d normal_a_;
    Eigen::Vector3d normal_b_;
};

// The device plate: a disc of radius r_d at the platform pose; the pad is pressed only where
// its undeformed nodes project inside the disc (rim-edge contact is ignored).
class PlateObstacle final : public Obstacle {
  public:
    PlateObstacle(const PlatformPose& pose, double plate_radius_m);
    double signedDistance(const Eigen::Vector3d& point_m, Eigen::Vector3d& normal) const override;

  private:
    Eigen::Vector3d centre_m_;
    Eigen::Vector3d normal_;  // towards the finger
    double radius_m_;
};

struct PadContact {
    Eigen::Vector3d force_on_finger_n{Eigen::Vector3d::Zero()};
    std::vector<bool> node_in_contact;
    int contact_count{0};
};

// How the simulation weights the samples it sends (docs/algorithms.md §3.2: area is the neutral
// choice, contact force the alternative).
//   kArea: the sample's share of skin area.
//   kContactForce: contact samples share their total area in proportion to their pressure;
//     non-contact samples keep their area.
//   kContactStiffness [DER]: area times the local contact stiffness dp/d(delta), taken at the
//     virtual indentation for contact samples and at zero for the others. With these weights
//     the Gauss-Newton normal equation of the plate height, sum_i w_i r_i = 0, is the
//     first-order condition that the device force equals the virtual one, so a geometric fit
//     also matches force for curved objects.
enum class SampleWeighting { kArea, kContactForce, kContactStiffness };

class FingertipContactModel {
  public:
    virtual ~FingertipContactModel() = default;
    [[nodiscard]] virtual PadContact press(const Obstacle& obstacle) const = 0;
    // The finger-pad samples the simulation would send to the device for this obstacle.
    [[nodiscard]] virtual msgs::ContactSurface contactSurface(const Obstacle& obstacle,
                                                              int sample_count,
                                                              SampleWeighting weighting) const = 0;
};

struct PadModelParameters {
    double contact_height_m{0.018};     // lowest pad point (finger_calibration.contact_height_m)
    double pad_radius_m{0.009};         // curvature radius of the pad
    double footprint_radius_m{0.0085};  // nodes cover the cap out to this radius from the axis
    double node_spacing_m{0.00025};
    double pressure_scale_pa{4000.0};
    double stiffening_depth_m{0.001};
};

class NonlinearPadModel final : public FingertipContactModel {
  public:
    explicit NonlinearPadModel(const PadModelParameters& parameters);
    PadContact press(const Obstacle& obstacle) const override;
    msgs::ContactSurface contactSurface(const Obstacle& obstacle, int sample_count,
                                        SampleWeighting weighting) const override;

    [[nodiscard]] double pressure(double depth_m) const;
    [[nodiscard]] double pressureSlope(double depth_m) const;  // dp/d(delta), Pa/m
    [[nodiscard]] const PadModelParameters& parameters() const { return parameters_; }
    [[nodiscard]] std::size_t nodeCount() const { return nodes_m_.size(); }
    // Undeformed pad surface point above (x, y).
    [[nodiscard]] Eigen::Vector3d surfacePoint(double x_m, double y_m) const;
    // Force of a flat, untilted plate pressed depth_m past first contact.
    [[nodiscard]] double flatPlateForce(double depth_m) const;

  private:
    PadModelParameters parameters_;
    std::vector<Eigen::Vector3d> nodes_m_;
    double node_area_m2_{0.0};
};

}  // namespace haptic::tactile
