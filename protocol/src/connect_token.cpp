#include "dsoc/protocol/connect_token.hpp"

#include "dsoc/common/read_file.hpp"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>

#include <cctype>
#include <chrono>
#include <stdexcept>

namespace dsoc::protocol {

namespace {

constexpr std::size_t kSignedBytes = 17;
constexpr std::size_t kMacBytes = 32;
static_assert(kSignedBytes + kMacBytes == kConnectTokenBytes);

void put_u64(std::uint8_t* out, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) {
        out[i] = static_cast<std::uint8_t>(v >> (8 * i));
    }
}

std::uint64_t get_u64(const std::uint8_t* in) {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) {
        v |= static_cast<std::uint64_t>(in[i]) << (8 * i);
    }
    return v;
}

std::array<std::uint8_t, kMacBytes> mac_of(const TokenKey& key, const std::uint8_t* data) {
    std::array<std::uint8_t, kMacBytes> mac{};
    unsigned int length = 0;
    if (HMAC(EVP_sha256(), key.bytes.data(), static_cast<int>(key.bytes.size()), data, kSignedBytes,
             mac.data(), &length) == nullptr ||
        length != kMacBytes) {
        throw std::runtime_error("HMAC-SHA256 failed in OpenSSL");
    }
    return mac;
}

int hex_digit(char c) {
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    return -1;
}

} // namespace

TokenKey generate_token_key() {
    TokenKey key;
    if (RAND_bytes(key.bytes.data(), static_cast<int>(key.bytes.size())) != 1) {
        throw std::runtime_error("OpenSSL RAND_bytes failed: no key generated");
    }
    return key;
}

std::string format_token_key(const TokenKey& key) {
    return to_hex(key.bytes);
}

bool parse_token_key(std::string_view text, TokenKey& key, std::string& error) {
    std::string digits;
    for (const char c : text) {
        if (std::isspace(static_cast<unsigned char>(c)) == 0) {
            digits.push_back(c);
        }
    }
    std::vector<std::uint8_t> bytes;
    if (!from_hex(digits, bytes)) {
        error = "a token key is hex digits only";
        return false;
    }
    if (bytes.size() != kTokenKeyBytes) {
        error = "a token key is " + std::to_string(2 * kTokenKeyBytes) + " hex digits, got " +
                std::to_string(digits.size());
        return false;
    }
    std::copy(bytes.begin(), bytes.end(), key.bytes.begin());
    return true;
}

bool load_token_key(const std::string& path, TokenKey& key, std::string& error) {
    std::string text;
    if (const std::string why = common::read_file(path, text); !why.empty()) {
        error = path + ": cannot read token key: " + why;
        return false;
    }
    if (!parse_token_key(text, key, error)) {
        error = path + ": " + error;
        return false;
    }
    return true;
}

std::vector<std::uint8_t> mint_connect_token(const TokenKey& key, const ConnectToken& token) {
    std::vector<std::uint8_t> out(kConnectTokenBytes);
    out[0] = kConnectTokenVersion;
    put_u64(out.data() + 1, token.client_id);
    put_u64(out.data() + 9, token.expires_unix_s);
    const auto mac = mac_of(key, out.data());
    std::copy(mac.begin(), mac.end(), out.begin() + kSignedBytes);
    return out;
}

TokenCheck verify_connect_token(const TokenKey& key, std::span<const std::uint8_t> bytes,
                                std::uint64_t now_unix_s) {
    TokenCheck check;
    if (bytes.empty()) {
        check.why = "no connect token (this server is not insecure)";
        return check;
    }
    if (bytes.size() != kConnectTokenBytes) {
        check.why = "connect token is " + std::to_string(bytes.size()) + " bytes, expected " +
                    std::to_string(kConnectTokenBytes);
        return check;
    }
    if (bytes[0] != kConnectTokenVersion) {
        check.why = "connect token version " + std::to_string(bytes[0]) + ", expected " +
                    std::to_string(kConnectTokenVersion);
        return check;
    }
    const auto mac = mac_of(key, bytes.data());
    if (CRYPTO_memcmp(mac.data(), bytes.data() + kSignedBytes, kMacBytes) != 0) {
        check.status = TokenStatus::bad_signature;
        check.why = "connect token signature does not match this server's key";
        return check;
    }
    check.token.client_id = get_u64(bytes.data() + 1);
    check.token.expires_unix_s = get_u64(bytes.data() + 9);
    if (check.token.client_id == 0) {
        check.status = TokenStatus::malformed; // never minted: 0 means "no client"
        check.why = "connect token for client id 0, which is reserved";
        return check;
    }
    if (now_unix_s >= check.token.expires_unix_s) {
        check.status = TokenStatus::expired;
        check.why = "connect token for client " + std::to_string(check.token.client_id) +
                    " expired " + std::to_string(now_unix_s - check.token.expires_unix_s) +
                    " s ago";
        return check;
    }
    check.status = TokenStatus::valid;
    return check;
}

std::uint64_t unix_now_s() {
    const auto now = std::chrono::system_clock::now().time_since_epoch();
    return static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::seconds>(now).count());
}

std::string to_hex(std::span<const std::uint8_t> bytes) {
    static constexpr char kDigits[] = "0123456789abcdef";
    std::string out;
    out.reserve(bytes.size() * 2);
    for (const std::uint8_t b : bytes) {
        out.push_back(kDigits[b >> 4]);
        out.push_back(kDigits[b & 15]);
    }
    return out;
}

bool from_hex(std::string_view hex, std::vector<std::uint8_t>& out) {
    out.clear();
    if (hex.size() % 2 != 0) {
        return false;
    }
    out.reserve(hex.size() / 2);
    for (std::size_t i = 0; i < hex.size(); i += 2) {
        const int hi = hex_digit(hex[i]);
        const int lo = hex_digit(hex[i + 1]);
        if (hi < 0 || lo < 0) {
            return false;
        }
        out.push_back(static_cast<std::uint8_t>(hi * 16 + lo));
    }
    return true;
}

} // namespace dsoc::protocol
