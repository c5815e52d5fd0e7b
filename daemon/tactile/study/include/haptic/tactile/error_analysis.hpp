#pragma once

// The error analysis of docs/algorithms.md §3.7 as a library, so the tool and the tests run the
// same procedure: each virtual object presses the fingertip model; the simulation's samples go to
// the optimiser and the two baselines; each method's servo angles go through forward
// kinematics and the plate at that pose presses the same fingertip model; the two contacts
// are compared. Not for the RT path (allocates).

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "haptic/tactile/contact_optimiser.hpp"
#include "haptic/tactile/fingertip_model.hpp"

namespace haptic::tactile {

struct ForceComparison {
    bool valid{false};                // false: the method produced no pose
    double force_error{0.0};          // |F_d - F_v| / |F_v|
    double magnitude_error{0.0};      // (|F_d| - |F_v|) / |F_v|, signed
    double direction_error_deg{0.0};  // 180 when the plate does not touch the pad
    double jaccard{0.0};              // overlap of the contact node sets
};

[[nodiscard]] ForceComparison compareWithVirtualContact(const ThimbleKinematics& kinematics,
                                                        const FingertipContactModel& finger,
                                                        const PadContact& virtual_contact,
                                                        const std::optional<PlatformDofs>& dofs);

struct AnalysisCase {
    std::string name;
    std::unique_ptr<Obstacle> object;
};

// Planes tilted 0-30 degrees, spheres of 5/10/20 mm (and a tilted 10 mm one), a 90-degree
// edge, all `indentation_m` past first touch of the pad; then two targets outside the
// workspace: a 45-degree plane and a plane 6 mm deep.
[[nodiscard]] std::vector<AnalysisCase> standardCases(const PadModelParameters& pad,
                                                      double indentation_m);

struct CaseResult {
    std::string name;
    double virtual_force_n{0.0};
    SolveReport optimiser_report;
    ForceComparison optimiser;
    ForceComparison geometric;
    ForceComparison force_normal;
    [[nodiscard]] bool reachable() const { return !optimiser_report.clamped; }
};

struct AnalysisSettings {
    int samples{64};
    SampleWeighting weighting{SampleWeighting::kContactStiffness};
    double finger_stiffness_n_per_m{0.0};  // for the force-normal baseline
};

// The plane-fit baseline always gets area weights (its definition: centroid and average
// normal); the optimiser and the force baseline get `settings.weighting`.
[[nodiscard]] std::vector<CaseResult> runErrorAnalysis(const ThimbleKinematics& kinematics,
                                                       const FingertipContactModel& finger,
                                                       ContactSurfaceOptimiser& optimiser,
                                                       const std::vector<AnalysisCase>& cases,
                                                       const AnalysisSettings& settings);

}  // namespace haptic::tactile
