#include "haptic/daemon/sim_input_validation.hpp"

#include <cmath>

namespace haptic::daemon {
namespace {

bool finite(double value) noexcept {
    return std::isfinite(value);
}

template <std::size_t N>
bool allFinite(const std::array<double, N>& values, std::size_t used = N) noexcept {
    for (std::size_t i = 0; i < used && i < N; ++i) {
        if (!finite(values[i])) {
            return false;
        }
    }
    return true;
}

// One rule for every direction the sim sends (sample normals, contact normals, joint axes):
// its length within 1e-3 of 1 (docs/hapticd.md). The sim normalises them; what comes through
// is normalised again where it is used.
bool unitLength(const std::array<double, 3>& v) noexcept {
    return std::abs(std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) - 1.0) <= 1e-3;
}

}  // namespace

std::string_view describe(InputRejection reason) noexcept {
    switch (reason) {
        case InputRejection::kNone:
            return "accepted";
        case InputRejection::kWrongDevice:
            return "source_id names another device";
        case InputRejection::kDofMismatch:
            return "dof differs from the device's joint count";
        case InputRejection::kNonFinite:
            return "NaN or Inf in the message";
        case InputRejection::kCountOverCapacity:
            return "count exceeds the array capacity";
        case InputRejection::kDegenerateConstraint:
            return "constraint normal has zero length, or its contact lies beyond a hand's reach";
        case InputRejection::kBadNormal:
            return "contact normal or joint axis is not unit length";
        case InputRejection::kNotNewer:
            return "seq does not advance and is no restart (a replay or a duplicate)";
        case InputRejection::kDelayed:
            return "older than sim_timeout_ms by its stamp (delayed)";
        case InputRejection::kBadStamp:
            return "stamp_ns is not positive";
        case InputRejection::kStampAhead:
            return "stamped ahead of the sim's clock by more than sim_timeout_ms (a stepped "
                   "clock or a corrupt stamp)";
        case InputRejection::kNegativeWeight:
            return "negative sample weight";
        case InputRejection::kOtherSchema:
            return "header.schema is not this build's (a sim from another release)";
        case InputRejection::kCount_:
            break;
    }
    return "unknown";
}

namespace {

// The schema first: in another release's layout every other field means something else.
InputRejection validateHeader(const msgs::MessageHeader& header,
                              std::string_view device_id) noexcept {
    if (header.schema != msgs::kSchema) {
        return InputRejection::kOtherSchema;
    }
    if (header.source_id.view() != device_id) {
        return InputRejection::kWrongDevice;
    }
    return InputRejection::kNone;
}

// The contact behind a row (msgs::ContactKinematics): joints within the device's and the
// array's, every slot finite (unused ones too: a NaN there would make every frame differ
// from the last), lengths and angles of a hand (gap and levers within 1 m, reference angles
// within 10 rad), a unit normal and unit axes (within 1e-3; the blend between frames
// interpolates them, the renderer normalises).
InputRejection validateContact(const msgs::ContactKinematics& contact, std::uint16_t dof) noexcept {
    if (contact.joints < 0 || static_cast<std::size_t>(contact.joints) > msgs::kMaxContactJoints ||
        contact.joints > dof) {
        return InputRejection::kCountOverCapacity;
    }
    if (!finite(contact.gap_m) || !allFinite(contact.normal) || !allFinite(contact.q_ref_rad)) {
        return InputRejection::kNonFinite;
    }
    for (std::size_t j = 0; j < msgs::kMaxContactJoints; ++j) {
        if (!allFinite(contact.axis[j]) || !allFinite(contact.lever_m[j])) {
            return InputRejection::kNonFinite;
        }
    }
    if (contact.joints == 0) {
        return InputRejection::kNone;  // no contact known: the row is all there is
    }
    if (!(std::abs(contact.gap_m) <= 1.0)) {
        return InputRejection::kDegenerateConstraint;
    }
    const auto joints = static_cast<std::size_t>(contact.joints);
    for (std::size_t j = 0; j < joints; ++j) {
        const auto& lever = contact.lever_m[j];
        if (!(std::abs(contact.q_ref_rad[j]) <= 10.0) ||
            !(lever[0] * lever[0] + lever[1] * lever[1] + lever[2] * lever[2] <= 1.0)) {
            return InputRejection::kDegenerateConstraint;
        }
        if (!unitLength(contact.axis[j])) {
            return InputRejection::kBadNormal;
        }
    }
    return unitLength(contact.normal) ? InputRejection::kNone : InputRejection::kBadNormal;
}

}  // namespace

InputRejection validate(const msgs::ConstraintSet& message, std::string_view device_id,
                        std::uint16_t joint_count) noexcept {
    if (const InputRejection header = validateHeader(message.header, device_id);
        header != InputRejection::kNone) {
        return header;
    }
    if (message.constraints.count > msgs::kMaxConstraints) {
        return InputRejection::kCountOverCapacity;
    }
    if (message.dof != joint_count || message.dof > msgs::kMaxJointDofs) {
        return InputRejection::kDofMismatch;
    }
    if (!allFinite(message.q_sim_rad, message.dof) ||
        !allFinite(message.reference_torque_nm, message.dof)) {
        return InputRejection::kNonFinite;
    }
    for (const auto& constraint : message.constraints) {
        // Every entry of a, the unused ones too (a NaN there would make every frame differ).
        if (!allFinite(constraint.a) || !finite(constraint.b)) {
            return InputRejection::kNonFinite;
        }
        double norm_squared = 0.0;
        for (std::size_t i = 0; i < message.dof; ++i) {
            norm_squared += constraint.a[i] * constraint.a[i];
        }
        if (!(norm_squared > 1e-24)) {
            return InputRejection::kDegenerateConstraint;
        }
        if (const InputRejection contact = validateContact(constraint.contact, message.dof);
            contact != InputRejection::kNone) {
            return contact;
        }
    }
    return InputRejection::kNone;
}

InputRejection validate(const msgs::ContactSurface& message, std::string_view device_id) noexcept {
    if (const InputRejection header = validateHeader(message.header, device_id);
        header != InputRejection::kNone) {
        return header;
    }
    if (message.samples.count > msgs::kMaxContactSamples) {
        return InputRejection::kCountOverCapacity;
    }
    if (!allFinite(message.reference_force_device_n) ||
        !allFinite(message.reference_moment_device_nm)) {
        return InputRejection::kNonFinite;
    }
    for (const auto& sample : message.samples) {
        if (!allFinite(sample.p_device_m) || !allFinite(sample.normal_device) ||
            !finite(sample.signed_distance_m) || !finite(sample.weight)) {
            return InputRejection::kNonFinite;
        }
        if (!unitLength(sample.normal_device)) {
            return InputRejection::kBadNormal;
        }
        if (sample.weight < 0.0) {
            return InputRejection::kNegativeWeight;
        }
    }
    return InputRejection::kNone;
}

}  // namespace haptic::daemon
