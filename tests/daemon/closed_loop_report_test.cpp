#include "closed_loop_report.hpp"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "contact_quality.hpp"
#include "telemetry_csv.hpp"

namespace haptic::ctl {
namespace {

using ::testing::HasSubstr;

// The first tick that renders a new tracker sample gives its latency: 90 Hz samples received
// 20 ms after their stamp (the tracker's own latency) and rendered 15 ms after that, except
// one received 10 ms after its stamp (so rendered 25 ms after receipt); a telemetry sample
// lost where a new tracker sample starts hides that one.
TEST(ClosedLoopReport, TrackerToCommandLatencyIsTakenWhereTheSampleChanges) {
    constexpr std::int64_t kOrigin = 5'000'000'000;  // monotonic time of the recording's start
    std::string csv = telemetryCsvHeader();
    msgs::TelemetrySample sample;
    sample.device_kind = msgs::DeviceKind::kExoskeleton;
    int samples = 0;
    for (int tick = 0; tick < 1000; ++tick) {
        sample.tick = static_cast<std::uint64_t>(tick);
        sample.stamp_ns = kOrigin + 1'000'000LL * tick;
        // Sample k (stamp 11 k ms) is rendered from tick 11 k + 35 on.
        if (tick >= 35 && (tick - 35) % 11 == 0) {
            const int k = (tick - 35) / 11;
            const std::int64_t stamp = kOrigin + 11'000'000LL * k;
            sample.tracking = {stamp, stamp + (k == 40 ? 10'000'000 : 20'000'000)};
            ++samples;
            if (k == 60) {
                continue;  // this telemetry sample was lost
            }
        }
        csv += telemetryCsvRow(sample, kOrigin);
    }
    const auto devices = readTelemetryCsv(csv);
    const TrackingLatency latency = trackingLatency(devices.at(0));
    EXPECT_EQ(latency.from_receipt_ms.count, static_cast<std::uint64_t>(samples - 1))
        << "the one at the lost telemetry sample is skipped";
    EXPECT_NEAR(latency.from_receipt_ms.p50, 15.0, 1e-6);
    EXPECT_NEAR(latency.from_receipt_ms.max, 25.0, 1e-6);
    EXPECT_NEAR(latency.from_sample_ms.p50, 35.0, 1e-6);
    EXPECT_NEAR(latency.from_sample_ms.max, 35.0, 1e-6);
    const std::string text = formatReport(devices, {}, {});
    EXPECT_NE(text.find("from handsim's receipt p50 15.0 ms"), std::string::npos) << text;

    EXPECT_EQ(latency.tracker_samples, static_cast<std::size_t>(samples))
        << "the one behind the lost telemetry sample is seen a tick late: counted, not measured";

    std::string scripted = telemetryCsvHeader();
    sample.tracking = {};
    scripted += telemetryCsvRow(sample, 0);
    const auto scripted_devices = readTelemetryCsv(scripted);
    EXPECT_EQ(trackingLatency(scripted_devices.at(0)).tracker_samples, 0U);
    EXPECT_NE(formatReport(scripted_devices, {}, {}).find("no tracker samples (scripted hand)"),
              std::string::npos);

    // Every 10th tick recorded: tracker samples, but none measurable, and the report says why.
    std::string decimated = telemetryCsvHeader();
    for (std::size_t row = 1; row < devices.at(0).column("tick").size(); row += 10) {
        sample.tick = static_cast<std::uint64_t>(devices.at(0).column("tick")[row]);
        sample.stamp_ns = kOrigin + 1'000'000LL * static_cast<std::int64_t>(sample.tick);
        const double sampled_s = devices.at(0).column("tracking_sampled_s")[row];
        sample.tracking = {
            kOrigin + static_cast<std::int64_t>(std::llround(sampled_s * 1e9)),
            kOrigin + static_cast<std::int64_t>(std::llround(sampled_s * 1e9)) + 20'000'000};
        decimated += telemetryCsvRow(sample, kOrigin);
    }
    const auto decimated_devices = readTelemetryCsv(decimated);
    const TrackingLatency none = trackingLatency(decimated_devices.at(0));
    EXPECT_EQ(none.from_receipt_ms.count, 0U);
    EXPECT_GT(none.tracker_samples, 50U);
    const std::string decimated_text = formatReport(decimated_devices, {}, {});
    EXPECT_NE(decimated_text.find("not measured"), std::string::npos) << decimated_text;
    EXPECT_EQ(decimated_text.find("scripted"), std::string::npos) << decimated_text;
}

TEST(ClosedLoopReport, ReadsTheRecordingBackAndComparesFeltWithReference) {
    std::string csv = telemetryCsvHeader();
    msgs::TelemetrySample sample;
    for (int i = 0; i < 100; ++i) {
        sample.tick = static_cast<std::uint64_t>(i);
        sample.stamp_ns = 1'000'000LL * i;
        sample.device_index = 0;
        sample.device_kind = msgs::DeviceKind::kExoskeleton;
        const bool contact = i >= 50;
        sample.exoskeleton.reference_actuator_force_n = contact ? -2.0 : 0.0;
        sample.exoskeleton.actuator_force_n = contact ? -1.5 : 0.0;      // 0.5 N short
        sample.exoskeleton.actuator_force_cmd_n = contact ? -1.6 : 0.0;  // one 1.6 N step
        sample.exoskeleton.ghost_torque_nm = {contact ? 0.003 : 0.0, contact ? 0.004 : 0.0, 0.0};
        sample.exoskeleton.energy_observer_j = -0.01 * i;   // the device gives energy
        sample.exoskeleton.environment_work_j = 0.004 * i;  // the moving objects put in less
        csv += telemetryCsvRow(sample, 0);
        sample.device_index = 1;
        sample.device_kind = msgs::DeviceKind::kThimble;
        sample.thimble.reference_force_device_n = {0.0, contact ? 0.6 : 0.0, contact ? 0.8 : 0.0};
        csv += telemetryCsvRow(sample, 0);
    }
    csv += "12,0.5,0,exo";  // a truncated last line is skipped
    const auto devices = readTelemetryCsv(csv);
    ASSERT_EQ(devices.size(), 2U);
    EXPECT_EQ(devices.at(0).kind, "exoskeleton");
    ASSERT_EQ(devices.at(0).column("time_s").size(), 100U);

    const ExoskeletonReport exo = exoskeletonReport(devices.at(0), {});
    EXPECT_EQ(exo.contact_ticks, 50U);
    EXPECT_NEAR(exo.mean_reference_n, 2.0, 1e-9);
    EXPECT_NEAR(exo.rms_error_n, 0.5, 1e-9);
    EXPECT_NEAR(exo.peak_error_n, 0.5, 1e-9);
    EXPECT_NEAR(exo.errorFraction(), 0.25, 1e-9);
    EXPECT_NEAR(exo.rms_ghost_torque_nm, 0.005, 1e-6);
    EXPECT_NEAR(exo.delivered_energy_j, 0.99, 1e-6);
    EXPECT_NEAR(exo.environment_work_j, 0.396, 1e-6);
    EXPECT_NEAR(exo.excessEnergy(), 0.594, 1e-6);
    EXPECT_NEAR(exo.carried_in_budget_j, 0.0, 1e-9);
    EXPECT_NEAR(exo.worst_balance_j, 0.594, 1e-9);        // active from the first tick on
    EXPECT_NEAR(exo.delivered_in_deficit_j, 0.98, 1e-9);  // every tick after the first
    EXPECT_EQ(exo.clamp_below_reference_ticks, 0U);
    EXPECT_NEAR(exo.largest_step_n, 1.6, 1e-9);
    EXPECT_EQ(exo.steps_over_rate_limit, 1U);

    const ThimbleReport thimble = thimbleReport(devices.at(1), {});
    EXPECT_EQ(thimble.contact_ticks, 50U);
    EXPECT_NEAR(thimble.mean_reference_force_n, 1.0, 1e-4);
    const std::string text = formatReport(devices, {}, {});
    EXPECT_NE(text.find("error RMS 0.500 N (25.0% of it)"), std::string::npos) << text;
    EXPECT_THROW((void)readTelemetryCsv("time,tick\n1,2\n"), std::runtime_error);
}

// A passive port may give more in a recording than the objects put in while it spends the
// budget it took before the recording began (a previous method's window): the report tells
// that from an active port by the balance counted from the enable, to the nJ.
TEST(ClosedLoopReport, APortSpendingABudgetCarriedInIsPassive) {
    std::string csv = telemetryCsvHeader();
    msgs::TelemetrySample sample;
    sample.device_index = 0;
    sample.device_kind = msgs::DeviceKind::kExoskeleton;
    for (int i = 0; i < 100; ++i) {
        sample.tick = static_cast<std::uint64_t>(i);
        sample.stamp_ns = 1'000'000LL * i;
        // Taken in before: 40 uJ; given back 0.25 uJ a tick, 10 uJ while the objects add 15.
        sample.exoskeleton.energy_observer_j = 40e-6 - 0.25e-6 * i;
        sample.exoskeleton.environment_work_j = 0.15e-6 * i;
        csv += telemetryCsvRow(sample, 0);
    }
    const ExoskeletonReport passive = exoskeletonReport(readTelemetryCsv(csv).at(0), {});
    EXPECT_NEAR(passive.excessEnergy(), 9.9e-6, 1e-12);
    EXPECT_NEAR(passive.carried_in_budget_j, 40e-6, 1e-12);
    EXPECT_NEAR(passive.worst_balance_j, -30.1e-6, 1e-12);
    EXPECT_EQ(passive.delivered_in_deficit_j, 0.0);
    EXPECT_NE(formatReport(readTelemetryCsv(csv), {}, {}).find("at most -3.01e-05 J"),
              std::string::npos);

    // The same budget overspent by 0.5 uJ at the end: active, though the excess is as small.
    sample.exoskeleton.energy_observer_j = -0.5e-6;
    sample.exoskeleton.environment_work_j = 0.0;
    sample.tick = 100;
    sample.stamp_ns = 100'000'000LL;
    csv += telemetryCsvRow(sample, 0);
    const ExoskeletonReport active = exoskeletonReport(readTelemetryCsv(csv).at(0), {});
    EXPECT_NEAR(active.worst_balance_j, 0.5e-6, 1e-12);
    EXPECT_EQ(active.delivered_in_deficit_j, 0.0) << "the deficit began on the last tick";

    // A deficit booked by the objects (their work falls), then 0.25 uJ delivered in it.
    sample.exoskeleton.environment_work_j = -1e-6;
    sample.tick = 101;
    csv += telemetryCsvRow(sample, 0);
    sample.exoskeleton.energy_observer_j = -0.75e-6;
    sample.tick = 102;
    csv += telemetryCsvRow(sample, 0);
    const ExoskeletonReport spending = exoskeletonReport(readTelemetryCsv(csv).at(0), {});
    EXPECT_NEAR(spending.worst_balance_j, 1.75e-6, 1e-12);
    EXPECT_NEAR(spending.delivered_in_deficit_j, 0.25e-6, 1e-12);

    // The port is disabled (both columns read 0: a new passivity interval), then enabled and
    // given 2 uJ by the objects, of which it delivers 1.5: the drop to 0 is neither delivered
    // energy nor the objects' work, and no delivery in deficit.
    const double delivered_before = spending.delivered_energy_j;
    const double work_before = spending.environment_work_j;
    sample.tick = 103;
    sample.exoskeleton.energy_observer_j = 0.0;
    sample.exoskeleton.environment_work_j = 0.0;
    csv += telemetryCsvRow(sample, 0);
    sample.tick = 104;
    sample.exoskeleton.environment_work_j = 2e-6;
    csv += telemetryCsvRow(sample, 0);
    sample.tick = 105;
    sample.exoskeleton.energy_observer_j = -1.5e-6;
    csv += telemetryCsvRow(sample, 0);
    const ExoskeletonReport reenabled = exoskeletonReport(readTelemetryCsv(csv).at(0), {});
    EXPECT_NEAR(reenabled.delivered_energy_j, delivered_before + 1.5e-6, 1e-12);
    EXPECT_NEAR(reenabled.environment_work_j, work_before + 2e-6, 1e-12);
    EXPECT_NEAR(reenabled.delivered_in_deficit_j, 0.25e-6, 1e-12);
    EXPECT_NEAR(reenabled.worst_balance_j, 1.75e-6, 1e-12);
}

// A recording of one thimble, "pad_device", one sample a millisecond from time_s 0 =
// CLOCK_MONOTONIC origin_ns (what a felt log is lined up by), with the reference force
// `reference(tick)` (device frame).
template <typename Reference>
std::string thimbleRecording(std::int64_t origin_ns, int ticks, Reference reference) {
    msgs::HapticStatus status;
    msgs::DeviceStatus thimble_status;
    thimble_status.device_id.assign("pad_device");
    thimble_status.kind = msgs::DeviceKind::kThimble;
    EXPECT_TRUE(status.devices.push_back(thimble_status));
    std::string csv = telemetryCsvProvenance("0.1.0", 0, origin_ns, &status) + telemetryCsvHeader();
    msgs::TelemetrySample sample;
    sample.device_index = 0;
    sample.device_kind = msgs::DeviceKind::kThimble;
    for (int i = 0; i < ticks; ++i) {
        sample.tick = static_cast<std::uint64_t>(i);
        sample.stamp_ns = origin_ns + 1'000'000LL * i;
        sample.thimble.reference_force_device_n = reference(i);
        csv += telemetryCsvRow(sample, origin_ns);
    }
    return csv;
}

// A thimble recording and the virtual user's felt log of the same run, on one monotonic
// clock: the felt pad force lines up with the ticks and is compared with the reference.
TEST(ClosedLoopReport, TheFeltLogOfTheThimbleLinesUpWithTheRecording) {
    const std::int64_t origin_ns = 7'000'000'000'123;
    // 0.5 N on the pad from tick 40.
    const std::string csv = thimbleRecording(origin_ns, 100, [](int i) {
        return std::array<double, 3>{0.0, 0.0, i >= 40 ? -0.5 : 0.0};
    });
    // The pad under the plate feels 0.4 N from tick 50 on (the plate arrives 10 ms late), logged
    // every millisecond half a tick before hapticd's ticks, up to tick 70 (the log then stops).
    std::string felt_log =
        "# hapticemu felt log\n"
        "stamp_ns,device,finger_penetration_m,pose_known,indentation_m,force_x_n,force_y_n,"
        "force_z_n,moment_x_nm,"
        "moment_y_nm,moment_z_nm\n";
    for (int i = -5; i <= 70; ++i) {
        const bool pressed = i >= 50;
        // Row 30 had no plate pose: its force is unknown, not 0 N.
        felt_log += fmt::format("{},pad_device,{},{},{},0.0,0.0,{},0,0,0\n",
                                origin_ns + 1'000'000LL * i - 500'000,
                                pressed ? 0.0025 : (i >= 45 ? 0.001 : 0.0), i == 30 ? 0 : 1,
                                pressed ? 0.0015 : 0.0, pressed ? -0.4 : 0.0);
    }
    // A last line cut short, as a reader racing the writer sees it: it stops inside force_z,
    // and a line with fewer than the eleven fields is skipped.
    felt_log += fmt::format("{},pad_device,0.002,1,0.001,0.0,0.0,-0.2", origin_ns + 70'500'000);

    // 76 whole rows after the header; the cut last line is not one.
    EXPECT_EQ(completeFeltLogRows(felt_log), 76U);
    auto devices = readTelemetryCsv(csv);
    const auto felt = readFeltLog(felt_log);
    ASSERT_EQ(felt.at("pad_device").stamp_ns.size(), 76U);
    ASSERT_EQ(attachFeltLog(devices, readRecordingInfo(csv), felt),
              std::vector<std::string>{"pad_device"});
    const auto& felt_z = devices.at(0).column("felt_force_z_n");
    EXPECT_EQ(felt_z[29], 0.0);
    EXPECT_TRUE(std::isnan(felt_z[30]));  // the row without a pose
    EXPECT_EQ(felt_z[31], 0.0);
    EXPECT_EQ(felt_z[49], 0.0);
    EXPECT_EQ(felt_z[50], -0.4);
    // The last row (69.5 ms) stands for the ticks up to 20 ms after it; later ones are
    // unknown, not zero.
    EXPECT_EQ(felt_z[89], -0.4);
    EXPECT_TRUE(std::isnan(felt_z[90]));

    // The finger reaches 1 mm into the object from tick 45, 2.5 mm from tick 50; known on the
    // ticks 0-89 (also on row 30's, which lacks only the pad's pose).
    const FingerPenetration penetration = fingerPenetration(devices.at(0));
    EXPECT_EQ(penetration.known, 90U);
    EXPECT_EQ(penetration.inside, 45U);
    EXPECT_DOUBLE_EQ(penetration.while_inside_m.p50, 0.0025);
    EXPECT_DOUBLE_EQ(penetration.while_inside_m.max, 0.0025);

    ContactQualitySettings thimble_settings;
    thimble_settings.clamp_n = 1.5;
    const ThimbleReport report = thimbleReport(devices.at(0), thimble_settings);
    EXPECT_EQ(report.contact_ticks, 60U);  // reference from tick 40
    EXPECT_EQ(report.felt_ticks, 50U);     // of those, felt known up to tick 89
    EXPECT_NEAR(report.mean_reference_force_n, 0.5, 1e-9);
    EXPECT_NEAR(report.mean_reference_on_felt_ticks_n, 0.5, 1e-9);
    EXPECT_NEAR(report.mean_felt_force_n, 40 * 0.4 / 50.0, 1e-9);
    // Ticks 40-49: error 0.5 N; 50-89: 0.1 N. The share is of the reference on those ticks.
    const double rms = std::sqrt((10 * 0.25 + 40 * 0.01) / 50.0);
    EXPECT_NEAR(report.rms_error_n, rms, 1e-9);
    EXPECT_NEAR(report.errorFraction(), rms / 0.5, 1e-9);
    EXPECT_NEAR(report.peak_error_n, 0.5, 1e-9);
    EXPECT_NEAR(report.peak_indentation_m, 0.0015, 1e-12);
    // Tick 30 (unknown) holds the last known |felt| (0 N); the ticks after the last known one
    // (89) are left out. So the chatter and limit figures see 0 N up to tick 49 and 0.4 N on
    // 50-89: one step, never at the 1.5 N limit.
    std::vector<double> held(90, 0.0);
    std::fill(held.begin() + 50, held.end(), 0.4);
    const ContactQuality expected = contactQuality(held, thimble_settings);
    EXPECT_EQ(report.felt_quality.ticks, 90U);
    EXPECT_EQ(report.felt_quality.contact_ticks, 40U);
    EXPECT_EQ(report.felt_quality.clamp_ticks, 0U);
    EXPECT_DOUBLE_EQ(report.felt_quality.chatter_rms_n, expected.chatter_rms_n);
    EXPECT_DOUBLE_EQ(report.felt_quality.mean_contact_force_n, 0.4);
    const std::string text = formatReport(devices, {}, thimble_settings);
    EXPECT_THAT(text, HasSubstr("felt vs reference, 50 contact ticks with a felt value"));
    EXPECT_THAT(text, HasSubstr("pad indented up to 1.50 mm"));
    EXPECT_THAT(text, HasSubstr("felt above 0.05 N on 40 ticks"));
    EXPECT_THAT(text, HasSubstr("the user's finger inside the scene's static objects on 50.0% "
                                "of 90 ticks; there p50 2.50 mm"));

    // A felt log for another device, a recording from before the origin line, not a felt log.
    auto unmatched = readTelemetryCsv(csv);
    const auto other_device = readFeltLog(
        "stamp_ns,device,finger_penetration_m,pose_known,indentation_m,force_x_n,force_y_n,"
        "force_z_n,moment_x_nm,"
        "moment_y_nm,moment_z_nm\n"
        "1,other,0,1,0,0,0,0,0,0,0\n");
    EXPECT_TRUE(attachFeltLog(unmatched, readRecordingInfo(csv), other_device).empty());
    EXPECT_THROW((void)attachFeltLog(unmatched, readRecordingInfo(telemetryCsvHeader()), felt),
                 std::runtime_error);
    EXPECT_THROW((void)readFeltLog(csv), std::runtime_error);
    // Without a felt log the report says how to get one; with one that has nothing in
    // contact, it says that instead.
    EXPECT_THAT(formatReport(readTelemetryCsv(csv), {}, thimble_settings),
                HasSubstr("felt pad force: no felt log"));
    auto no_felt_in_contact = readTelemetryCsv(csv);
    const auto early_log = readFeltLog(
        "stamp_ns,device,finger_penetration_m,pose_known,indentation_m,force_x_n,force_y_n,"
        "force_z_n,moment_x_nm,"
        "moment_y_nm,moment_z_nm\n" +
        fmt::format("{},pad_device,0,1,0,0,0,0,0,0,0\n", origin_ns));
    ASSERT_EQ(attachFeltLog(no_felt_in_contact, readRecordingInfo(csv), early_log).size(), 1U);
    EXPECT_THAT(formatReport(no_felt_in_contact, {}, thimble_settings),
                HasSubstr("the felt log has no value on any contact tick"));
    // Its one row stands for the ticks up to 20 ms after it: 0-20.
    EXPECT_THAT(formatReport(no_felt_in_contact, {}, thimble_settings),
                HasSubstr("the user's finger never inside the scene's static objects (21 ticks)"));
}

// A finger sliding on an object feels friction across the pad; the thimble's plate pushes the
// pad along the plate's normal. The report splits the error along the plate's push (the
// force's size) and across it (the reference's direction off the push), the two adding up to
// the whole error.
TEST(ClosedLoopReport, TheThimblesErrorIsSplitAlongAndAcrossThePlatesPush) {
    const std::int64_t origin_ns = 5'000'000'000'000;
    // From tick 10 the sim's pad is pressed 0.4 N into the pad (−z) and dragged 0.2 N along −x
    // and 0.1 N along +y.
    const std::array<double, 3> reference{-0.2, 0.1, -0.4};
    const double reference_n = std::hypot(reference[0], reference[1], reference[2]);
    const std::string csv = thimbleRecording(
        origin_ns, 70, [&](int i) { return i >= 10 ? reference : std::array<double, 3>{}; });
    // The plate, tilted so its push lies along the reference, presses 0.3 N on ticks 20-59;
    // nothing is felt before (no push felt yet: the untilted plate's −z stands for it) or after
    // (the last push felt stands). Row 40 feels 0.5 mN along +x, below the floor that gives a
    // direction (the push stays); row 45 has no plate pose (its tick is unknown, left out).
    const double felt_n = 0.3;
    const double faint_n = 5e-4;
    std::string felt_log =
        "stamp_ns,device,finger_penetration_m,pose_known,indentation_m,force_x_n,force_y_n,"
        "force_z_n,moment_x_nm,moment_y_nm,moment_z_nm\n";
    for (int i = -5; i < 70; ++i) {
        const double scale = i >= 20 && i < 60 ? felt_n / reference_n : 0.0;
        std::array<double, 3> felt{scale * reference[0], scale * reference[1],
                                   scale * reference[2]};
        if (i == 40) {
            felt = {faint_n, 0.0, 0.0};
        }
        felt_log += fmt::format("{},pad_device,0,{},0,{},{},{},0,0,0\n",
                                origin_ns + 1'000'000LL * i - 500'000, i == 45 ? 0 : 1, felt[0],
                                felt[1], felt[2]);
    }
    auto devices = readTelemetryCsv(csv);
    ASSERT_EQ(attachFeltLog(devices, readRecordingInfo(csv), readFeltLog(felt_log)),
              std::vector<std::string>{"pad_device"});
    const ThimbleReport report = thimbleReport(devices.at(0), {});
    ASSERT_EQ(report.felt_ticks, 59U);
    // Ticks 10-19, pushed along −z: 0.4 N short along it, the drag (0.2, −0.1) across it.
    // Ticks 20-59 but 40 and 45: along the reference, 0.3 N against its |F|, nothing across.
    // Tick 40: the faint force against the reference, split along the reference's direction
    // u. Ticks 60-69: the whole reference along the last push, nothing felt.
    const double faint_along_u = faint_n * reference[0] / reference_n;
    const double along_squared =
        (10 * 0.4 * 0.4 + 38 * std::pow(felt_n - reference_n, 2) +
         std::pow(faint_along_u - reference_n, 2) + 10 * reference_n * reference_n) /
        59.0;
    const double across_squared =
        (10 * (0.2 * 0.2 + 0.1 * 0.1) + faint_n * faint_n - faint_along_u * faint_along_u) / 59.0;
    EXPECT_NEAR(report.rms_error_along_push_n, std::sqrt(along_squared), 1e-5);
    EXPECT_NEAR(report.rms_error_across_push_n, std::sqrt(across_squared), 1e-5);
    EXPECT_NEAR(std::hypot(report.rms_error_along_push_n, report.rms_error_across_push_n),
                report.rms_error_n, 1e-12);
    EXPECT_NEAR(report.alongPushFraction(), std::sqrt(along_squared) / reference_n, 1e-5);
    EXPECT_NEAR(report.acrossPushFraction(), std::sqrt(across_squared) / reference_n, 1e-5);
    EXPECT_THAT(formatReport(devices, {}, {}),
                HasSubstr(fmt::format(
                    "along the plate's push {:.3f} N RMS ({:.1f}%); across it {:.3f} N "
                    "RMS ({:.1f}%): the reference's direction",
                    std::sqrt(along_squared), 100.0 * std::sqrt(along_squared) / reference_n,
                    std::sqrt(across_squared), 100.0 * std::sqrt(across_squared) / reference_n)));
}

TEST(ContactQuality, AHeldContactForceHasNoChatterAndIsNotAtTheClamp) {
    const std::vector<double> held(3000, -2.0);
    const ContactQuality quality = contactQuality(held);
    EXPECT_EQ(quality.ticks, 3000U);
    EXPECT_EQ(quality.contact_ticks, 3000U);
    EXPECT_EQ(quality.clamp_ticks, 0U);
    EXPECT_DOUBLE_EQ(quality.mean_contact_force_n, 2.0);
    EXPECT_LT(quality.chatter_rms_n, 1e-12);
    // A contact that builds up and releases smoothly over a second is not chatter either;
    // only ticks in contact count.
    std::vector<double> press(3000, 0.0);
    for (std::size_t i = 1000; i < 2000; ++i) {
        press[i] = -2.0 * std::pow(std::sin(std::numbers::pi * (i - 1000.0) / 1000.0), 2);
    }
    const ContactQuality smooth = contactQuality(press);
    EXPECT_NEAR(static_cast<double>(smooth.contact_ticks), 900.0, 20.0);  // |F| > 0.05 N
    EXPECT_LT(smooth.chatterFraction(), 0.01);
}

TEST(ContactQuality, BangBangBetweenZeroAndTheClampIsChatterAtTheClamp) {
    // The demo's old failure: the force jumps between 0 and the 10 N clamp every few ticks.
    std::vector<double> force(3000, 0.0);
    for (std::size_t i = 0; i < force.size(); ++i) {
        force[i] = (i / 4) % 2 == 0 ? -10.0 : -0.5;
    }
    const ContactQuality quality = contactQuality(force);
    EXPECT_EQ(quality.contact_ticks, 3000U);
    EXPECT_NEAR(quality.clampFraction(), 0.5, 0.01);
    EXPECT_GT(quality.chatterFraction(), 0.5);
    ContactQualitySettings looser;
    looser.clamp_n = 20.0;
    EXPECT_EQ(contactQuality(force, looser).clamp_ticks, 0U);
}

}  // namespace
}  // namespace haptic::ctl
