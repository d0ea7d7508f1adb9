// dsoc-token: makes token keys and mints connect tokens for dsoc-server.
//
//   dsoc-token keygen --out server.key             # a fresh secret (file mode 0600)
//   dsoc-token mint --key-file server.key --client-id 42 --ttl 300
//   dsoc-token check --key-file server.key <hex token>
//
// Tokens are printed as hex: a game backend hands them to its clients, which put the
// bytes in ClientHello.connect_token (dsoc-simclient --token / --token-key-file).
// Exit status (dsoc/cli/program.hpp): 0 done (check: the token is valid), 1 check found
// the token invalid or the key could not be written, 2 bad usage or an unreadable key.

#include "dsoc/cli/program.hpp"
#include "dsoc/protocol/connect_token.hpp"

#include <CLI/CLI.hpp>

#include <sys/stat.h>

#include <cstdio>
#include <fstream>
#include <iostream>

namespace {

using namespace dsoc::protocol;
using dsoc::cli::exit_failure;
using dsoc::cli::exit_ok;
using dsoc::cli::exit_usage;

int keygen(const std::string& out_path) {
    const std::string text = format_token_key(generate_token_key()) + "\n";
    if (out_path.empty()) {
        std::cout << text;
        return exit_ok;
    }
    const mode_t old_mask = ::umask(077); // the key is a secret: owner-only from the start
    std::ofstream out(out_path, std::ios::trunc);
    out << text;
    out.close();
    ::umask(old_mask);
    if (!out) {
        std::cerr << "dsoc-token: cannot write " << out_path << "\n";
        return exit_failure;
    }
    return exit_ok;
}

int mint(const std::string& key_file, std::uint64_t client_id, std::int64_t ttl_s) {
    TokenKey key;
    std::string error;
    if (!load_token_key(key_file, key, error)) {
        std::cerr << "dsoc-token: " << error << "\n";
        return exit_usage;
    }
    const ConnectToken token{client_id, unix_now_s() + static_cast<std::uint64_t>(ttl_s)};
    std::cout << to_hex(mint_connect_token(key, token)) << "\n";
    return exit_ok;
}

int check(const std::string& key_file, const std::string& hex) {
    TokenKey key;
    std::string error;
    if (!load_token_key(key_file, key, error)) {
        std::cerr << "dsoc-token: " << error << "\n";
        return exit_usage;
    }
    std::vector<std::uint8_t> bytes;
    if (!from_hex(hex, bytes)) {
        std::cerr << "dsoc-token: the token is not hex\n";
        return exit_usage;
    }
    const std::uint64_t now = unix_now_s();
    const TokenCheck result = verify_connect_token(key, bytes, now);
    if (result.status != TokenStatus::valid) {
        std::cout << "invalid: " << result.why << "\n";
        return exit_failure;
    }
    std::cout << "valid: client " << result.token.client_id << ", expires in "
              << (result.token.expires_unix_s - now) << " s (unix " << result.token.expires_unix_s
              << ")\n";
    return exit_ok;
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"dsoc-token: token keys and connect tokens for dsoc-server"};
    dsoc::cli::set_up(app, "dsoc-token");
    app.require_subcommand(1);

    std::string out_path;
    auto* keygen_cmd = app.add_subcommand("keygen", "Print or write a fresh random token key");
    keygen_cmd->add_option("--out", out_path, "Write the key to this file (mode 0600)");

    std::string key_file;
    std::uint64_t client_id = 0;
    std::int64_t ttl_s = 300;
    auto* mint_cmd = app.add_subcommand("mint", "Print a connect token for one client id");
    mint_cmd->add_option("--key-file", key_file, "The server's token key file")->required();
    mint_cmd->add_option("--client-id", client_id, "Client id the token grants (>= 1)")
        ->required()
        ->check(CLI::Range(std::uint64_t{1}, std::numeric_limits<std::uint64_t>::max()));
    mint_cmd->add_option("--ttl", ttl_s, "Lifetime from now [s]")
        ->capture_default_str()
        ->check(CLI::Range(std::int64_t{1}, std::int64_t{365} * 24 * 3600));

    std::string token_hex;
    auto* check_cmd = app.add_subcommand("check", "Verify a token and print what it grants");
    check_cmd->add_option("--key-file", key_file, "The server's token key file")->required();
    check_cmd->add_option("token", token_hex, "The token in hex")->required();

    if (const auto stop = dsoc::cli::parse(app, argc, argv)) {
        return *stop;
    }
    if (keygen_cmd->parsed()) {
        return keygen(out_path);
    }
    if (mint_cmd->parsed()) {
        return mint(key_file, client_id, ttl_s);
    }
    return check(key_file, token_hex);
}
