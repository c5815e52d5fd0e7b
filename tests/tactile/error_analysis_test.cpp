#include "haptic/tactile/error_analysis.hpp"

#include <gtest/gtest.h>

#include <map>

#include "haptic/config/device.hpp"

namespace haptic::tactile {
namespace {

// Holds the error-analysis claims of docs/benchmarks.md against regressions (stand-in pad model).
class ErrorAnalysisTest : public ::testing::Test {
  protected:
    static constexpr double kIndentationM = 0.0015;
    config::ThimbleConfig config{config::loadDeviceConfig(HAPTIC_THIMBLE_CONFIG).thimble()};
    ThimbleKinematics kinematics{config};
    NonlinearPadModel pad{PadModelParameters{}};
    // Given the stand-in pad's own law, as tactile_error_analysis does (the shipped law is the
    // FEM's, judged by FemErrorAnalysis against the FEM).
    ContactSurfaceOptimiser optimiser{kinematics, [this] {
                                          auto settings = OptimiserSettings::fromConfig(config);
                                          settings.pad_stiffening_depth_m =
                                              pad.parameters().stiffening_depth_m;
                                          return settings;
                                      }()};

    std::map<std::string, CaseResult> run() {
        const AnalysisSettings settings{config.optimiser.pad_samples,
                                        SampleWeighting::kContactStiffness,
                                        pad.flatPlateForce(kIndentationM) / kIndentationM};
        std::map<std::string, CaseResult> out;
        for (auto& r : runErrorAnalysis(kinematics, pad, optimiser,
                                        standardCases(pad.parameters(), kIndentationM), settings)) {
            out.emplace(r.name, r);
        }
        return out;
    }
};

TEST_F(ErrorAnalysisTest, OptimiserMatchesReachableContactsAtLeastAsWellAsTheBaselines) {
    const auto results = run();
    ASSERT_EQ(results.size(), 11U);
    for (const char* plane : {"plane 0 deg", "plane 10 deg"}) {
        const CaseResult& r = results.at(plane);
        EXPECT_TRUE(r.reachable()) << plane;
        EXPECT_LT(r.optimiser.force_error, 1e-3) << plane;
        EXPECT_LT(r.optimiser.force_error, r.force_normal.force_error) << plane;
    }
    for (const char* curved :
         {"sphere r=5 mm", "sphere r=10 mm", "sphere r=20 mm", "edge 90 deg"}) {
        const CaseResult& r = results.at(curved);
        EXPECT_TRUE(r.reachable()) << curved;
        EXPECT_LT(r.optimiser.force_error, r.geometric.force_error) << curved;
        EXPECT_LT(r.optimiser.force_error, r.force_normal.force_error) << curved;
    }
}

TEST_F(ErrorAnalysisTest, TargetsOutsideTheWorkspaceAreClampedAndStillRendered) {
    const auto results = run();
    for (const char* outside : {"plane 45 deg (> max tilt)", "plane 6 mm deep (> max indent)"}) {
        const CaseResult& r = results.at(outside);
        EXPECT_FALSE(r.reachable()) << outside;
        EXPECT_TRUE(r.optimiser.valid) << outside;
        EXPECT_TRUE(r.optimiser_report.converged) << outside;
    }
    EXPECT_LT(results.at("plane 45 deg (> max tilt)").optimiser.force_error,
              results.at("plane 45 deg (> max tilt)").geometric.force_error);
}

}  // namespace
}  // namespace haptic::tactile
