#pragma once
// One headless simulated client: connects, says hello, sends a wandering input
// every tick, decodes the compact snapshots into its own replica of the world and
// checks the protocol's invariants - including, when it asks the server for audits,
// that every replicated pose is within half a quantum of the server's own.

#include "dsoc/protocol/compact_snapshot.hpp"
#include "dsoc/protocol/framing.hpp"
#include "dsoc/protocol/messages.hpp"
#include "dsoc/simclient/client_stats.hpp"
#include "dsoc/simclient/load_config.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>

#include <array>
#include <chrono>
#include <memory>
#include <random>
#include <unordered_map>
#include <vector>

namespace dsoc::simclient {

class SimClient : public std::enable_shared_from_this<SimClient> {
public:
    SimClient(boost::asio::io_context& io, const LoadConfig& config, int index);

    /// Resolves and connects; the rest follows from the server's answers.
    void start();
    /// Says goodbye (Disconnect client_quit), then reads until the server closes.
    void stop();

    [[nodiscard]] const ClientStats& stats() const { return stats_; }
    [[nodiscard]] bool connected() const { return state_ == State::active; }
    [[nodiscard]] bool finished() const { return state_ == State::closed; }
    /// Entities in the replica right now.
    [[nodiscard]] std::size_t known() const { return replica_.size(); }
    /// The replica (quantized poses as decoded).
    [[nodiscard]] const protocol::SnapshotDecoder& replica() const { return replica_; }

private:
    enum class State : std::uint8_t { idle, connecting, awaiting_hello, active, stopping, closed };

    void on_connected();
    void read_some();
    void handle(const protocol::pb::Envelope& message);
    void apply_snapshot(const protocol::pb::Snapshot& snapshot);
    void schedule_input();
    void send_input();
    void send(const protocol::pb::Envelope& message);
    void write_next();
    void error(const std::string& kind);
    void close();

    boost::asio::io_context& io_;
    const LoadConfig& config_;
    int index_;
    State state_ = State::idle;
    boost::asio::ip::tcp::socket socket_;
    boost::asio::steady_timer input_timer_;
    boost::asio::steady_timer close_timer_;
    protocol::FrameDecoder decoder_;
    std::array<std::uint8_t, 16 * 1024> read_buffer_{}; // a read may hold several frames
    protocol::pb::Envelope incoming_;
    std::vector<std::uint8_t> pending_;   // frames not yet handed to the socket
    std::vector<std::uint8_t> in_flight_; // the frames of the write in progress
    bool writing_ = false;
    bool goodbye_sent_ = false;
    protocol::SnapshotDecoder replica_;
    ClientStats stats_;
    std::uint64_t last_snapshot_tick_ = 0;
    std::uint64_t input_seq_ = 0;
    int tick_rate_ = 30;
    std::chrono::steady_clock::time_point active_since_;
    std::chrono::steady_clock::time_point last_snapshot_at_;
    std::chrono::steady_clock::time_point next_input_at_;
    std::mt19937_64 rng_;
    float wish_yaw_deg_ = 0.0f;
    int ticks_until_turn_ = 0;
};

} // namespace dsoc::simclient
