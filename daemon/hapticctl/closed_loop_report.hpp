#pragma once

// The end-to-end figures of one recorded run (hapticctl record), per device: what the finger
// felt against the reference the simulation computed (docs/hapticctl.md, "plot").
//
// Exoskeleton, on the ticks where the reference or the felt force exceeds the contact
// threshold ("contact"):
//   felt       the force the actuator reports (exo_actuator_force_n);
//   reference  B^+ tau_ref, the actuator force that best gives the sim's fully actuated
//              reference torque (exo_reference_actuator_force_n);
//   error      RMS and peak of felt - reference, and RMS as a share of the mean |reference|;
//   ghost      RMS of |ghost torque|: the felt joint torque orthogonal to the reference;
//   clamp      commanded force at the clamp while |reference| < 80 % of it (share of contact);
//   chatter    contact_quality.hpp, on the commanded force;
//   energy     net energy the device delivered to the finger: minus the change of the port's
//              passivity observer over the run (> 0: the device gave energy); and the work the
//              sim's moving objects did on the coupling (the passivity controller's credit):
//              a passive rendering delivers at most that much;
//   steps      the largest change of the command between consecutive ticks, and how many
//              changes exceed the rate limit (the safety stage lets a force fall towards zero
//              faster than that; a rise never).
// Thimble, on the ticks where the reference or the felt pad force exceeds the threshold:
//   reference  the net force the object applies to the sim's pad (thimble_reference_force_*);
//   felt       the force the virtual user's own pad feels under the plate (hapticemu
//              --felt-log, attachFeltLog: a Hertz pad, not the optimiser's model), at the
//              felt log's last row at or before the tick;
//   error      RMS and peak of |felt - reference| (vectors, device frame), and RMS as a share
//              of the mean |reference|;
//   chatter, clamp  of |felt| where it exceeds the threshold, against the pad force limit.
// Both, with a felt log: how deep the user's finger (rigid, at its actual pose) reached into
// the scene's static objects (fingerPenetration).
//   Without a felt log only the reference is reported.
// Both: the tracker-to-command latency. On the first tick whose sim input follows a new
// tracker sample (tracking_sampled_s changes), the time from when handsim's reader received
// that sample, and from the sample's own stamp (which adds the tracker's own latency), to
// that tick: the first command computed from the sample. Recorded runs on one host only (the
// stamps are the sim host's monotonic clock).

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "contact_quality.hpp"
#include "haptic/common/statistics.hpp"

namespace haptic::ctl {

// The columns of one device in a recorded CSV, by name (telemetryCsvHeader()).
struct DeviceColumns {
    std::string kind;  // "exoskeleton" or "thimble"
    std::map<std::string, std::vector<double>, std::less<>> values;
    [[nodiscard]] const std::vector<double>& column(std::string_view name) const;
};

// Rows per device index. Throws std::runtime_error when the header lacks a column.
[[nodiscard]] std::map<int, DeviceColumns> readTelemetryCsv(std::string_view csv);

// Milliseconds, one value per tracker sample that reached a command.
struct TrackingLatency {
    common::PercentileSummary from_receipt_ms;
    common::PercentileSummary from_sample_ms;
    // New tracker samples in the recording, measured or not (0: a scripted hand). Only those
    // seen on the tick right after the previous one are measured, so a recording of every Nth
    // tick (loop.telemetry_decimation) has samples but no latency.
    std::size_t tracker_samples{0};
};
[[nodiscard]] TrackingLatency trackingLatency(const DeviceColumns& device);

struct ExoskeletonReport {
    ContactQuality quality;        // of the commanded force
    std::size_t contact_ticks{0};  // reference or felt above the threshold
    double mean_reference_n{0.0};
    double rms_error_n{0.0};
    double peak_error_n{0.0};
    double rms_ghost_torque_nm{0.0};
    std::size_t clamp_below_reference_ticks{0};
    // Over the recording, summed over the port's enable intervals in it.
    double delivered_energy_j{0.0};
    double environment_work_j{0.0};
    // Delivered beyond what the moving objects put in over the recording. It can be > 0 for a
    // passive port: the port spends the budget it was given before the recording began.
    [[nodiscard]] double excessEnergy() const noexcept {
        return delivered_energy_j - environment_work_j;
    }
    // The passivity balance, counted from the port's enable (the passivity controller's
    // interval, port_safety.hpp): delivered minus the moving objects' work. At the first
    // sample its negative is the budget carried into the recording; the largest over the
    // samples > 0 means the device gave more than it was given at that moment (active).
    double carried_in_budget_j{0.0};
    double worst_balance_j{0.0};
    // What the port delivered on ticks that began with the balance > 0 (in deficit, the
    // passivity controller lets no force spend): the controller's failures. A deficit itself
    // can arise without them, from the objects' motion debited after the tick. Counted over
    // consecutive samples only (a lower bound when telemetry samples were lost).
    double delivered_in_deficit_j{0.0};
    double largest_step_n{0.0};
    std::size_t steps_over_rate_limit{0};
    [[nodiscard]] double errorFraction() const noexcept {
        return mean_reference_n > 0.0 ? rms_error_n / mean_reference_n : 0.0;
    }
    [[nodiscard]] double clampBelowReferenceFraction() const noexcept {
        return contact_ticks == 0 ? 0.0
                                  : static_cast<double>(clamp_below_reference_ticks) /
                                        static_cast<double>(contact_ticks);
    }
};

struct ThimbleReport {
    std::size_t ticks{0};
    // Reference |F| or a known felt |F| above the threshold.
    std::size_t contact_ticks{0};
    double mean_reference_force_n{0.0};  // over the contact ticks
    double peak_reference_force_n{0.0};
    // From the felt log (attachFeltLog), over the contact ticks with a known felt force.
    bool felt_attached{false};
    std::size_t felt_ticks{0};
    double mean_felt_force_n{0.0};
    double mean_reference_on_felt_ticks_n{0.0};
    double rms_error_n{0.0};
    double peak_error_n{0.0};
    // The error split by the plate's push (the felt force's direction, which the plate's normal
    // sets; where less than 1 mN is felt, the last one felt, at first the untilted plate's −z):
    // along it, (felt − reference)·push, the force's size (|felt| − reference·push where the
    // felt force lies along the push); across it, the rest of felt − reference (the
    // reference's component off the push, there), its direction: a plate posed to the
    // contact's geometry (the optimiser) pushes along the contact normal, so a sliding
    // finger's friction lands here, and only a plate tilted along the force itself would
    // render it. rms_error_n² = along² + across² on every tick.
    double rms_error_along_push_n{0.0};
    double rms_error_across_push_n{0.0};
    // Of |felt| over every tick (an unknown one holding the last known value), by
    // contactQuality's own rule: the ticks with |felt| above the threshold, clamp = the pad
    // force limit.
    ContactQuality felt_quality;
    double peak_indentation_m{0.0};
    // RMS error as a share of the mean |reference| on the same ticks.
    [[nodiscard]] double errorFraction() const noexcept {
        return mean_reference_on_felt_ticks_n > 0.0 ? rms_error_n / mean_reference_on_felt_ticks_n
                                                    : 0.0;
    }
    [[nodiscard]] double alongPushFraction() const noexcept {
        return mean_reference_on_felt_ticks_n > 0.0
                   ? rms_error_along_push_n / mean_reference_on_felt_ticks_n
                   : 0.0;
    }
    [[nodiscard]] double acrossPushFraction() const noexcept {
        return mean_reference_on_felt_ticks_n > 0.0
                   ? rms_error_across_push_n / mean_reference_on_felt_ticks_n
                   : 0.0;
    }
};

// What a recording's '#' lines say: the monotonic stamp of time_s = 0 and each device's name.
struct RecordingInfo {
    std::int64_t origin_ns{-1};  // -1: the recording predates the line
    std::map<int, std::string> device_names;
};
[[nodiscard]] RecordingInfo readRecordingInfo(std::string_view csv);

// hapticemu --felt-log: per device name, the rows in time order; a row without a pad contact
// (pose_known 0: not a thimble, or no plate pose) has NaN force and indentation.
struct FeltSeries {
    std::vector<std::int64_t> stamp_ns;
    std::vector<double> finger_penetration_m;
    std::vector<std::array<double, 3>> force_n;
    std::vector<double> indentation_m;
};
// Throws std::runtime_error when the text is not a felt log.
[[nodiscard]] std::map<std::string, FeltSeries, std::less<>> readFeltLog(std::string_view csv);
// Data lines after the header that end in a newline (the header is gnuplot's point 0).
[[nodiscard]] std::size_t completeFeltLogRows(std::string_view csv);

// Adds finger_penetration_m to each device of `devices` the log names, and felt_force_{x,y,z}_n
// and felt_indentation_m to each such thimble (NaN where the log has no row within 20 ms
// before the tick). Returns the names of the devices that got them. Throws std::runtime_error when
// the recording has no origin line or names no devices.
std::vector<std::string> attachFeltLog(std::map<int, DeviceColumns>& devices,
                                       const RecordingInfo& recording,
                                       const std::map<std::string, FeltSeries, std::less<>>& felt);

[[nodiscard]] ExoskeletonReport exoskeletonReport(const DeviceColumns& device,
                                                  const ContactQualitySettings& settings);
[[nodiscard]] ThimbleReport thimbleReport(const DeviceColumns& device,
                                          const ContactQualitySettings& settings);

// How deep the user's finger reached into the scene's static objects (finger_penetration_m,
// from the felt log): over the ticks with a known value, the share inside and, while inside,
// the percentiles in metres. known = 0: no such column or no value.
struct FingerPenetration {
    std::size_t known{0};
    std::size_t inside{0};
    common::PercentileSummary while_inside_m;
};
[[nodiscard]] FingerPenetration fingerPenetration(const DeviceColumns& device);

// The report as text, one block per device. `thimble_settings.clamp_n`: the thimble's pad force
// limit (safety.max_force_n).
[[nodiscard]] std::string formatReport(const std::map<int, DeviceColumns>& devices,
                                       const ContactQualitySettings& settings,
                                       const ContactQualitySettings& thimble_settings);

}  // namespace haptic::ctl
