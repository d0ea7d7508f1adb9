#include "dsoc/inspect/client_view.hpp"

#include <algorithm>

namespace dsoc::inspect {

const char* to_string(EntityState s) noexcept {
    switch (s) {
    case EntityState::replicated_visible:
        return "replicated_visible";
    case EntityState::replicated_lookahead:
        return "replicated_lookahead";
    case EntityState::replicated_held:
        return "replicated_held";
    case EntityState::replicated_rule:
        return "replicated_rule";
    case EntityState::replicated_heard:
        return "replicated_heard";
    case EntityState::hidden_tbv:
        return "hidden_tbv";
    case EntityState::hidden_expired:
        return "hidden_expired";
    case EntityState::not_replicated:
        return "not_replicated";
    }
    return "?";
}

std::size_t ClientView::count(EntityState s) const {
    return static_cast<std::size_t>(std::count_if(
        entities.begin(), entities.end(), [s](const EntityView& e) { return e.state == s; }));
}

} // namespace dsoc::inspect
