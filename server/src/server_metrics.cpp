// Server::render_metrics: the server's state as Prometheus metrics.

#include "dsoc/server/server.hpp"
#include "dsoc/server/snapshot_pacer.hpp"

#include <fmt/format.h>

namespace dsoc::server {

std::string Server::render_metrics() const {
    // Closed connections are counted in stats_, the live ones here.
    ServerStats live;
    std::size_t queued = 0;
    for (const auto& [id, session] : sessions_) {
        if (session->state() == Connection::State::closed) {
            continue; // in stats_ already (on_closed), until apply_leaves() erases it
        }
        add_session_counts(*session, live);
        queued += session->queued_bytes();
    }
    const auto d = [](auto v) { return static_cast<double>(v); };

    PrometheusText out;
    out.histogram("dsoc_tick_duration_seconds",
                  "Work time of each server tick (movement, interest, snapshots).",
                  stats_.tick_duration);
    out.histogram("dsoc_culling_duration_seconds",
                  "Wall time per tick of the policy's begin_tick and the parallel phase: interest "
                  "evaluation (culling) and snapshot building for all clients, on the worker pool.",
                  stats_.culling_duration);
    out.histogram("dsoc_prepare_duration_seconds",
                  "Wall time per tick before the parallel phase, on the I/O thread: joins, inputs, "
                  "the world's step, snapshot offers and the shared preparation.",
                  stats_.prepare_duration);
    out.histogram("dsoc_handover_duration_seconds",
                  "Wall time per tick of the hand-over after the parallel phase: snapshot frames "
                  "handed to the sockets, the trace, the leaves.",
                  stats_.handover_duration);
    out.histogram("dsoc_handover_wait_seconds",
                  "Wall time per tick from the parallel phase's end to the hand-over's start: how "
                  "long the finished snapshots waited for the I/O thread.",
                  stats_.handover_wait);
    out.counter("dsoc_ticks_total", "Ticks run.", d(stats_.ticks));
    out.counter("dsoc_late_ticks_total",
                "Ticks that started more than one period late, or in place of skipped ones.",
                d(stats_.late_ticks));
    out.counter("dsoc_skipped_ticks_total",
                "Ticks dropped because the loop fell a whole period or more behind.",
                d(stats_.skipped_ticks));
    out.counter("dsoc_culling_cheapest_client_ticks_total",
                "Client-ticks given the policy's cheapest conservative answer because their turn "
                "came after the tick's culling budget (culling_budget).",
                d(stats_.cheapest_client_ticks));
    out.counter("dsoc_spectating_client_ticks_total",
                "Client-ticks sent the view of another entity than the client's own (spectators, "
                "ClientInput.watch).",
                d(stats_.spectating_client_ticks));
    out.counter("dsoc_heard_entities_total",
                "Entities in sent snapshots only because the client hears them (heard tier: a "
                "coarse position, no angles), summed over snapshots.",
                d(stats_.heard_entities_sent));
    out.gauge("dsoc_clients", "Clients in the game (after a valid hello).", d(clients_.size()));
    out.gauge("dsoc_connections", "Open connections, including those still in the handshake.",
              d(sessions_.size()));
    out.gauge("dsoc_pending_connections",
              "TCP connections waiting for their hello (max_pending_connections).",
              d(pending_.size()));
    out.gauge("dsoc_entities", "Entities in the world (bots and players).",
              d(world_.entities().size()));
    out.counter("dsoc_frags_total",
                "Entities killed by shots (shot_damage), each respawned at a spawn point.",
                d(world_.frags()));
    // As of the last hand-over: during a phase the jobs are changing them.
    out.gauge("dsoc_tbvs_alive", "Live Temporal Bounding Volume groups over all clients.",
              d(tbvs_alive_));
    out.gauge("dsoc_send_queue_bytes", "Unsent bytes queued for all clients.", d(queued));
    out.counter("dsoc_clients_accepted_total", "Connections accepted.", d(stats_.clients_accepted));
    out.counter("dsoc_bytes_sent_total", "Bytes sent to clients, frame headers included.",
                d(stats_.bytes_sent + live.bytes_sent));
    out.counter("dsoc_bytes_received_total", "Bytes received from clients.",
                d(stats_.bytes_received + live.bytes_received));
    out.counter("dsoc_snapshots_sent_total", "Snapshots sent.", d(stats_.snapshots_sent));
    out.counter("dsoc_entity_updates_sent_total", "Entity enters and updates sent.",
                d(stats_.entity_updates_sent));
    out.counter("dsoc_snapshot_writes_queued_total",
                "Snapshots the kernel did not take whole at the hand-over (a full socket buffer): "
                "the rest waited in the client's send queue.",
                d(stats_.snapshot_writes_queued));
    out.counter("dsoc_snapshots_dropped_total",
                "Snapshots not sent: not built because the client's previous one was still "
                "unsent (TCP) or its pace skipped them (UDP: dsoc_udp_snapshots_paced_total), "
                "or built but not taken whole by the kernel (UDP).",
                d(stats_.snapshots_dropped + live.snapshots_dropped));
    out.counter("dsoc_inputs_dropped_total", "Client messages over the per-second cap.",
                d(stats_.inputs_dropped + live.inputs_dropped));
    out.counter("dsoc_inputs_clamped_total", "Inputs with an out-of-range field clamped.",
                d(stats_.inputs_clamped + live.inputs_clamped));
    std::vector<std::pair<MetricLabels, double>> disconnects;
    for (const auto& [reason, count] : stats_.disconnects) {
        disconnects.push_back({{{"reason", reason}}, d(count)});
    }
    out.counter_family("dsoc_disconnects_total", "Closed connections by reason.", disconnects);
    if (udp_) {
        out.counter("dsoc_udp_datagrams_received_total", "Datagrams received on the UDP port.",
                    d(udp_->datagrams_received()));
        out.counter_family(
            "dsoc_udp_snapshots_total",
            "Snapshots built for UDP clients and handed to the socket (a datagram the kernel "
            "refuses still counts): coded against the newest frame the client "
            "acknowledged (baseline), or whole (none acknowledged, or too old: a late client).",
            {{{{"coded", "against_baseline"}}, d(stats_.acked_snapshots_against_baseline)},
             {{{"coded", "whole"}}, d(stats_.acked_snapshots_whole)}});
        out.counter_family(
            "dsoc_udp_snapshots_paced_total",
            fmt::format("Snapshots not built for UDP clients whose acknowledgements aged "
                        "(SnapshotPacer): lagging, over {} ticks older than the least age the "
                        "client showed lately (a snapshot every {} ticks), or behind, over the "
                        "unacked window of half a second of ticks, {} to {} (every {}).",
                        SnapshotPacer::kLagMargin, SnapshotPacer::kLaggingInterval,
                        SnapshotPacer::unacked_window_at(1), SnapshotPacer::unacked_window_at(1000),
                        SnapshotPacer::kBehindInterval),
            {{{{"pace", "lagging"}},
              d(stats_.snapshots_paced.lagging + live.snapshots_paced.lagging)},
             {{{"pace", "behind"}},
              d(stats_.snapshots_paced.behind + live.snapshots_paced.behind)}});
        out.counter("dsoc_udp_baseline_age_ticks_total",
                    "Ticks from the baseline to the snapshot, summed over the snapshots coded "
                    "against one: divided by their count, how late acknowledgements arrive.",
                    d(stats_.acked_baseline_age_ticks));
        out.counter("dsoc_udp_enters_deferred_total",
                    "Entities left out of a snapshot for want of room: more wanted to enter "
                    "than one snapshot takes (a crowd comes into view), or than its "
                    "datagrams carry; they enter later, nearest first.",
                    d(stats_.acked_enters_deferred));
        out.counter("dsoc_udp_updates_deferred_total",
                    "Update entries left out of a snapshot because its datagrams could not "
                    "carry them all; the entity stays known, at its prediction, and a later "
                    "snapshot's entry repairs it (nearest first, the longest waiting before).",
                    d(stats_.acked_updates_deferred));
        out.counter("dsoc_udp_challenges_sent_total",
                    "UDP handshake challenges sent (one per request within its address's budget).",
                    d(udp_->challenges_sent()));
        std::vector<std::pair<MetricLabels, double>> drops;
        for (std::size_t r = 0; r < kUdpDropReasons; ++r) {
            drops.push_back(
                {{{"reason", udp_drop_name(static_cast<UdpDrop>(r))}}, d(udp_->drops()[r])});
        }
        out.counter_family("dsoc_udp_datagrams_dropped_total",
                           "UDP datagrams dropped unanswered, by reason.", drops);
    }
    if (feed_) {
        const WorldFeedStats w = feed_->stats();
        out.histogram("dsoc_gateway_world_hop_seconds",
                      "Per tick, from the world process encoding the tick to this gateway handing "
                      "its last snapshot to the kernel (one host's monotonic clock).",
                      stats_.world_hop);
        out.counter("dsoc_gateway_world_ticks_total",
                    "World ticks received from the world process (decoded, for this world).",
                    d(w.ticks_received));
        out.counter("dsoc_gateway_world_ticks_skipped_total",
                    "World ticks replaced by a newer one before they were served (the gateway "
                    "fell behind and skipped to the newest).",
                    d(w.ticks_skipped));
        out.counter("dsoc_gateway_bad_messages_total",
                    "Messages from NATS that did not decode, were of another world, went back in "
                    "time or jumped further ahead than the world's clock allows.",
                    d(w.bad_messages));
        out.counter("dsoc_gateway_id_blocks_total",
                    "Blocks of entity ids the world process reserved for this gateway.",
                    d(w.id_blocks));
        out.gauge("dsoc_gateway_ids_left", "Reserved entity ids not given to a player yet.",
                  d(w.ids_left));
        out.counter("dsoc_gateway_joins_resent_total",
                    "Joins sent again: a world tick lacked the player a second after its join "
                    "was sent (lost, or the world had removed this gateway's players).",
                    d(w.joins_resent));
        out.counter("dsoc_gateway_leaves_resent_total",
                    "Leaves sent again: a world tick still showed the player a second after its "
                    "leave was sent.",
                    d(w.leaves_resent));
        out.counter("dsoc_gateway_joins_abandoned_total",
                    fmt::format("Joins given up after {} re-sends no world tick showed: the "
                                "world no longer held the player's id for this gateway (it "
                                "forgot the gateway while it was cut off); the session ended "
                                "with try_again.",
                                GatewayIds::kJoinResends),
                    d(w.joins_abandoned));
        out.counter("dsoc_gateway_ids_voided_total",
                    "Reserved entity ids not given out yet, dropped as void with an abandoned "
                    "join's block (the world no longer held them for this gateway).",
                    d(w.ids_voided));
        out.counter("dsoc_gateway_world_restarts_total",
                    "New world process instances followed (the world restarted): every session "
                    "then ended with world_restarted.",
                    d(w.world_restarts));
        out.counter("dsoc_gateway_world_resyncs_total",
                    "The world instance followed taken up anew at its present tick: its ticks "
                    "had all gone back from the last one taken for a second (that one forged).",
                    d(w.world_resyncs));
        out.counter("dsoc_gateway_other_instance_total",
                    "World ticks of another world instance, refused while the one followed was "
                    "live (a restarted world's first; steadily: a second world process on this "
                    "world name), and id blocks of an instance not followed.",
                    d(w.other_instance));
        out.counter("dsoc_gateway_messages_not_sent_total",
                    "Joins, inputs, leaves or reserve requests the NATS link refused.",
                    d(w.not_sent));
        out.counter("dsoc_gateway_nats_disconnects_total", "Connections to NATS lost.",
                    d(w.nats_disconnects));
        out.counter("dsoc_gateway_nats_reconnects_total", "Connections to NATS regained.",
                    d(w.nats_reconnects));
    }
    return out.text();
}

} // namespace dsoc::server
