#include "dsoc/simclient/input_model.hpp"

#include <algorithm>
#include <cmath>

namespace dsoc::simclient {

namespace {
constexpr float kPi = 3.14159265358979f;
/// How often a wanderer fires, on average. [Units: 1/s]
constexpr double kWandererShotsPerSecond = 0.5;

void set_move(protocol::pb::ClientInput& input, float yaw_deg, float speed) {
    input.set_move_x(speed * std::cos(yaw_deg * kPi / 180.0f));
    input.set_move_y(speed * std::sin(yaw_deg * kPi / 180.0f));
}
} // namespace

InputModel::InputModel(Behaviour behaviour, std::uint64_t seed)
    : behaviour_(behaviour), rng_(seed) {}

void InputModel::next(protocol::pb::ClientInput& input, int tick_rate, const KnownEntities& replica,
                      std::uint32_t own_entity) {
    if (behaviour_ == Behaviour::camper) {
        camp(input, tick_rate);
    } else if (behaviour_ == Behaviour::spectator) {
        spectate(input, tick_rate, replica, own_entity);
    } else {
        wander(input, tick_rate);
    }
}

void InputModel::spectate(protocol::pb::ClientInput& input, int tick_rate,
                          const KnownEntities& replica, std::uint32_t own_entity) {
    if (--ticks_left_ <= 0 || (watch_ != 0 && !replica.knows(watch_))) {
        players_.clear();
        replica.players(players_);
        std::erase(players_, own_entity);
        std::sort(players_.begin(), players_.end()); // the map's order is not the seed's
        watch_ = 0;
        if (!players_.empty()) {
            std::uniform_int_distribution<std::size_t> pick(0, players_.size() - 1);
            watch_ = players_[pick(rng_)];
        }
        std::uniform_int_distribution<int> hold(5 * tick_rate, 10 * tick_rate);
        ticks_left_ = watch_ != 0 ? hold(rng_) : tick_rate; // none known: look again in 1 s
    }
    input.set_move_x(0.0f);
    input.set_move_y(0.0f);
    input.set_watch(watch_);
}

void InputModel::wander(protocol::pb::ClientInput& input, int tick_rate) {
    if (--ticks_left_ <= 0) {
        std::uniform_real_distribution<float> yaw(-180.0f, 180.0f);
        std::uniform_int_distribution<int> hold(tick_rate, 3 * tick_rate);
        yaw_deg_ = yaw(rng_);
        ticks_left_ = hold(rng_);
    }
    set_move(input, yaw_deg_, 1.0f);
    input.set_view_yaw(yaw_deg_);
    input.set_fire(std::bernoulli_distribution(kWandererShotsPerSecond / tick_rate)(rng_));
}

void InputModel::camp(protocol::pb::ClientInput& input, int tick_rate) {
    if (--ticks_left_ <= 0) {
        stepping_ = !stepping_;
        if (stepping_) {
            std::uniform_real_distribution<float> yaw(-180.0f, 180.0f);
            std::uniform_int_distribution<int> step(tick_rate / 5 + 1, tick_rate / 2 + 1);
            yaw_deg_ = yaw(rng_);
            ticks_left_ = step(rng_);
        } else {
            std::uniform_int_distribution<int> pause(2 * tick_rate, 5 * tick_rate);
            ticks_left_ = pause(rng_);
        }
    }
    set_move(input, yaw_deg_, stepping_ ? 0.33f : 0.0f);
    // The view sweeps 30 degrees a second, wrapped into [-180, 180).
    view_deg_ += 30.0f / static_cast<float>(tick_rate);
    if (view_deg_ >= 180.0f) {
        view_deg_ -= 360.0f;
    }
    input.set_view_yaw(view_deg_);
}

} // namespace dsoc::simclient
