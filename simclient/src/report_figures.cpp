#include "dsoc/simclient/report_figures.hpp"

#include "dsoc/simclient/load_report.hpp"

namespace dsoc::simclient {

namespace {

using Read = std::function<FigureValue(const LoadReport&)>;

/// One statistic of a Summary member (the checking clients' entity samples, a time's
/// spread): absent when the run took no sample, rather than 0.
Figure of_summary(std::string name, Dimension dimension, std::string meaning,
                  common::Summary LoadReport::*member, double common::Summary::*field) {
    return {std::move(name), dimension, std::move(meaning), [member, field](const LoadReport& r) {
                const common::Summary& s = r.*member;
                return FigureValue{s.*field, s.count > 0};
            }};
}

/// interarrival_mean .. interarrival_max from one Summary member; absent without samples.
void add_summary(std::vector<Figure>& out, const std::string& prefix, const std::string& what,
                 common::Summary LoadReport::*member) {
    const std::pair<const char*, double common::Summary::*> stats[] = {
        {"mean", &common::Summary::mean},
        {"p50", &common::Summary::p50},
        {"p95", &common::Summary::p95},
        {"p99", &common::Summary::p99},
        {"max", &common::Summary::max}};
    for (const auto& [stat, field] : stats) {
        out.push_back(of_summary(prefix + "_" + stat, Dimension::time,
                                 std::string(stat) + " of " + what, member, field));
    }
}

Figure plain(const char* name, const char* meaning, std::function<double(const LoadReport&)> f) {
    return {name, Dimension::plain, meaning, [f = std::move(f)](const LoadReport& r) {
                return FigureValue{f(r), true};
            }};
}

std::vector<Figure> make_figures() {
    std::vector<Figure> f;
    add_summary(f, "interarrival", "the time between a client's snapshots as it handled them",
                &LoadReport::snapshot_interarrival_ms);
    add_summary(f, "socket_interarrival",
                "the time between a client's snapshots as its socket received them (UDP)",
                &LoadReport::snapshot_socket_interarrival_ms);
    add_summary(f, "handling_lag",
                "a snapshot's wait between the client's socket and its handling (UDP)",
                &LoadReport::handling_lag_ms);
    add_summary(f, "rtt", "the ping round trip", &LoadReport::rtt_ms);
    add_summary(f, "connect_time", "a session's start to its server hello",
                &LoadReport::connect_ms);
    f.push_back({"bytes_down_per_client", Dimension::byte_rate,
                 "bytes received per connected client per second", [](const LoadReport& r) {
                     return FigureValue{r.bytes_down_per_client_s, true};
                 }});
    f.push_back({"bytes_up_per_client", Dimension::byte_rate,
                 "bytes sent per connected client per second", [](const LoadReport& r) {
                     return FigureValue{r.bytes_up_per_client_s, true};
                 }});
    f.push_back({"failure_rate", Dimension::ratio,
                 "failed sessions over sessions that connected or failed", [](const LoadReport& r) {
                     return FigureValue{r.failure_rate(), true};
                 }});
    f.push_back(plain("entity_updates_per_client", "enters and updates per client per second",
                      [](const LoadReport& r) { return r.entity_updates_per_client_s; }));
    f.push_back(of_summary("entities_known_mean", Dimension::plain,
                           "entities a checking client knows, mean over its snapshots",
                           &LoadReport::entities_known, &common::Summary::mean));
    f.push_back(of_summary("entities_known_p95", Dimension::plain,
                           "entities a checking client knows, p95 over its snapshots",
                           &LoadReport::entities_known, &common::Summary::p95));
    f.push_back(
        of_summary("entities_heard_mean", Dimension::plain,
                   "entities a checking client knows only by hearing, mean over its snapshots",
                   &LoadReport::entities_heard, &common::Summary::mean));
    f.push_back(plain("snapshots", "snapshots received by all clients",
                      [](const LoadReport& r) { return static_cast<double>(r.snapshots); }));
    f.push_back(plain("sessions", "sessions started",
                      [](const LoadReport& r) { return static_cast<double>(r.clients); }));
    f.push_back(plain("connected", "sessions that got a server hello",
                      [](const LoadReport& r) { return static_cast<double>(r.connected); }));
    f.push_back(plain("peak_connected", "most sessions connected at once",
                      [](const LoadReport& r) { return static_cast<double>(r.peak_connected); }));
    f.push_back(plain("failures", "failed sessions, any reason",
                      [](const LoadReport& r) { return static_cast<double>(r.failures); }));
    f.push_back(plain("connect_failures", "sessions failed before their hello",
                      [](const LoadReport& r) { return static_cast<double>(r.connect_failures); }));
    f.push_back(plain("protocol_errors", "protocol errors seen by clients",
                      [](const LoadReport& r) { return static_cast<double>(r.protocol_errors); }));
    f.push_back(
        plain("unexpected_disconnects", "sessions lost or dropped",
              [](const LoadReport& r) { return static_cast<double>(r.unexpected_disconnects); }));
    f.push_back(plain("max_audit_error", "largest replica error, quanta",
                      [](const LoadReport& r) { return r.max_audit_error; }));
    return f;
}

} // namespace

const std::vector<Figure>& report_figures() {
    static const std::vector<Figure> figures = make_figures();
    return figures;
}

const Figure* find_figure(std::string_view name) {
    for (const Figure& f : report_figures()) {
        if (f.name == name) {
            return &f;
        }
    }
    return nullptr;
}

std::string figure_names() {
    std::string out;
    for (const Figure& f : report_figures()) {
        out += (out.empty() ? "" : ", ") + f.name;
    }
    return out;
}

} // namespace dsoc::simclient
