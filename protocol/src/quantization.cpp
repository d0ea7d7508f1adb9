#include "dsoc/protocol/quantization.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dsoc::protocol {

namespace {

constexpr float kMinQuantum = 1.0f / 1024.0f;
constexpr float kMaxQuantum = 64.0f;
constexpr float kMaxHeardQuantum = 1024.0f;
constexpr std::uint32_t kMinSteps = 256;
constexpr std::uint32_t kMaxSteps = 65536;

std::int32_t round_clamped(double v) {
    if (!std::isfinite(v)) {
        return 0;
    }
    const double limit = kMaxQuantizedCoordinate;
    return static_cast<std::int32_t>(std::lround(std::clamp(v, -limit, limit)));
}

bool quantum_ok(float q) {
    return std::isfinite(q) && q >= kMinQuantum && q <= kMaxQuantum;
}

} // namespace

std::vector<std::string> validate(const QuantizationSettings& s, const std::string& prefix) {
    std::vector<std::string> problems;
    static constexpr const char* kNames[kLodTiers] = {
        "position_quantum_near", "position_quantum_mid", "position_quantum_far"};
    for (std::size_t t = 0; t < kLodTiers; ++t) {
        const float q = s.position_quantum[t];
        if (!quantum_ok(q)) {
            problems.push_back(prefix + kNames[t] + ": must be 1/1024..64 world units, got " +
                               std::to_string(q));
        } else if (t > 0 && quantum_ok(s.position_quantum[t - 1]) &&
                   q < s.position_quantum[t - 1]) {
            problems.push_back(prefix + kNames[t] + ": must be at least " + kNames[t - 1] +
                               " (a farther tier is never finer)");
        }
    }
    const float far = s.position_quantum[kLodTiers - 1];
    if (!std::isfinite(s.heard_quantum) || s.heard_quantum > kMaxHeardQuantum ||
        !(s.heard_quantum >= std::min(far, kMaxQuantum))) {
        problems.push_back(prefix +
                           "heard_quantum: must be position_quantum_far..1024 world "
                           "units (hearing is never finer than sight), got " +
                           std::to_string(s.heard_quantum));
    }
    if (s.angle_steps < kMinSteps || s.angle_steps > kMaxSteps) {
        problems.push_back(prefix + "angle_steps: must be 256..65536 steps per turn, got " +
                           std::to_string(s.angle_steps));
    }
    return problems;
}

void to_message(const QuantizationSettings& s, pb::Quantization& out) {
    out.Clear();
    for (const float q : s.position_quantum) {
        out.add_position_quantum(q);
    }
    out.set_angle_steps(s.angle_steps);
    out.set_heard_quantum(s.heard_quantum);
}

bool from_message(const pb::Quantization& m, QuantizationSettings& out, std::string& why) {
    if (m.position_quantum_size() != static_cast<int>(kLodTiers)) {
        why = "quantization has " + std::to_string(m.position_quantum_size()) +
              " position quanta; expected " + std::to_string(kLodTiers);
        return false;
    }
    QuantizationSettings s;
    for (std::size_t t = 0; t < kLodTiers; ++t) {
        s.position_quantum[t] = m.position_quantum(static_cast<int>(t));
    }
    s.angle_steps = m.angle_steps();
    s.heard_quantum = m.heard_quantum();
    if (const auto problems = validate(s, "quantization."); !problems.empty()) {
        why = problems.front();
        return false;
    }
    out = s;
    return true;
}

QuantizedPose quantize(const Pose& p, float quantum, std::uint32_t steps) {
    const double inv = 1.0 / static_cast<double>(quantum);
    const double per_degree = static_cast<double>(steps) / 360.0;
    QuantizedPose q;
    q.x = round_clamped(static_cast<double>(p.x) * inv);
    q.y = round_clamped(static_cast<double>(p.y) * inv);
    q.z = round_clamped(static_cast<double>(p.z) * inv);
    const auto n = static_cast<std::int64_t>(steps);
    const std::int64_t yaw = round_clamped(static_cast<double>(p.yaw_deg) * per_degree);
    q.yaw = static_cast<std::int32_t>(((yaw % n) + n) % n);
    q.pitch = round_clamped(static_cast<double>(p.pitch_deg) * per_degree);
    return q;
}

QuantizedPose quantize(const Pose& pose, const QuantizationSettings& settings, std::uint8_t tier) {
    if (tier == kHeardTier) {
        return quantize({pose.x, pose.y, pose.z, 0.0f, 0.0f}, settings.heard_quantum,
                        settings.angle_steps);
    }
    return quantize(pose, settings.position_quantum[tier], settings.angle_steps);
}

Pose dequantize(const QuantizedPose& q, float quantum, std::uint32_t steps) {
    const auto quantum_d = static_cast<double>(quantum);
    const double degrees_per_step = 360.0 / static_cast<double>(steps);
    Pose p;
    p.x = static_cast<float>(q.x * quantum_d);
    p.y = static_cast<float>(q.y * quantum_d);
    p.z = static_cast<float>(q.z * quantum_d);
    double yaw = q.yaw * degrees_per_step;
    if (yaw >= 180.0) {
        yaw -= 360.0;
    }
    p.yaw_deg = static_cast<float>(yaw);
    p.pitch_deg = static_cast<float>(q.pitch * degrees_per_step);
    return p;
}

std::uint32_t quantize_extent(float half_extent, float quantum) {
    if (!std::isfinite(half_extent) || half_extent <= 0.0f) {
        return 0;
    }
    const double q = std::ceil(static_cast<double>(half_extent) / static_cast<double>(quantum));
    return static_cast<std::uint32_t>(std::min(q, static_cast<double>(kMaxQuantizedCoordinate)));
}

double quantization_error(const Pose& replica, const Pose& exact, float quantum,
                          std::uint32_t steps) {
    const auto quantum_d = static_cast<double>(quantum);
    const double steps_per_degree = static_cast<double>(steps) / 360.0;
    auto along = [&](float a, float b) { return std::abs(static_cast<double>(a) - b) / quantum_d; };
    double yaw = std::fmod(static_cast<double>(replica.yaw_deg) - exact.yaw_deg, 360.0);
    if (yaw > 180.0) {
        yaw -= 360.0;
    } else if (yaw < -180.0) {
        yaw += 360.0;
    }
    const double pitch = static_cast<double>(replica.pitch_deg) - exact.pitch_deg;
    double worst =
        std::max({along(replica.x, exact.x), along(replica.y, exact.y), along(replica.z, exact.z),
                  std::abs(yaw) * steps_per_degree, std::abs(pitch) * steps_per_degree});
    if (std::isnan(worst)) {
        worst = std::numeric_limits<double>::infinity();
    }
    return worst;
}

} // namespace dsoc::protocol
