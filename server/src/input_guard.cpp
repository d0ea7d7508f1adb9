#include "dsoc/server/input_guard.hpp"

#include <algorithm>
#include <cmath>

namespace dsoc::server {

namespace pb = protocol::pb;

InputVerdict sanitize_input(pb::ClientInput& in) {
    InputVerdict verdict;
    const struct {
        const char* name;
        float value;
    } fields[] = {{"move_x", in.move_x()},
                  {"move_y", in.move_y()},
                  {"move_z", in.move_z()},
                  {"view_yaw", in.view_yaw()},
                  {"view_pitch", in.view_pitch()}};
    for (const auto& f : fields) {
        if (!std::isfinite(f.value)) {
            verdict.usable = false;
            verdict.why = std::string("client_input.") + f.name + " is not a finite number";
            return verdict;
        }
    }
    // Length in double: float components up to 3.4e38 would overflow a float sum.
    const double x = in.move_x();
    const double y = in.move_y();
    const double z = in.move_z();
    const double length = std::sqrt(x * x + y * y + z * z);
    if (length > 1.0 + 1e-6) { // float rounding: (0.6f, 0.8f) is length 1
        in.set_move_x(static_cast<float>(x / length));
        in.set_move_y(static_cast<float>(y / length));
        in.set_move_z(static_cast<float>(z / length));
        ++verdict.clamped_fields;
    }
    const float yaw = in.view_yaw();
    if (yaw < -180.0f || yaw >= 180.0f) {
        float wrapped = std::remainder(yaw, 360.0f); // [-180, 180]
        if (wrapped >= 180.0f) {
            wrapped -= 360.0f;
        }
        in.set_view_yaw(wrapped); // the protocol's normal form, not an out-of-range value
    }
    const float pitch = in.view_pitch();
    if (pitch < -90.0f || pitch > 90.0f) {
        in.set_view_pitch(std::clamp(pitch, -90.0f, 90.0f));
        ++verdict.clamped_fields;
    }
    return verdict;
}

InputRateLimiter::InputRateLimiter(int per_second, Clock::time_point now)
    : per_second_(static_cast<double>(std::max(per_second, 1))), tokens_(per_second_),
      last_refill_(now), window_start_(now) {}

InputRateLimiter::Decision InputRateLimiter::on_message(Clock::time_point now) {
    if (now > last_refill_) {
        const double elapsed = std::chrono::duration<double>(now - last_refill_).count();
        tokens_ = std::min(per_second_, tokens_ + elapsed * per_second_);
        last_refill_ = now;
    }
    if (now - window_start_ >= std::chrono::seconds(1)) {
        window_start_ = now;
        drops_in_window_ = 0;
    }
    if (tokens_ >= 1.0) {
        tokens_ -= 1.0;
        return Decision::accept;
    }
    ++dropped_total_;
    ++drops_in_window_;
    return static_cast<double>(drops_in_window_) > per_second_ ? Decision::flood : Decision::drop;
}

} // namespace dsoc::server
