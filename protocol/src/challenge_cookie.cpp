#include "dsoc/protocol/challenge_cookie.hpp"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>

#include <cstring>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace dsoc::protocol {

namespace {

constexpr std::string_view kCookieLabel = "dsoc-cookie-1";
constexpr std::size_t kTimeBytes = 8;
constexpr std::size_t kCookieMacBytes = kCookieBytes - kTimeBytes;

void put_le(std::vector<std::uint8_t>& out, std::uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) {
        out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
}

std::array<std::uint8_t, 32> cookie_mac(const TokenKey& key, const SourceAddress& from,
                                        std::uint64_t nonce, std::uint64_t issued_ms) {
    // The label, the address, its port, the nonce and the time, little-endian.
    constexpr int kPortBytes = 2;
    constexpr int kNonceBytes = 8;
    std::vector<std::uint8_t> data;
    data.reserve(kCookieLabel.size() + from.address.size() + kPortBytes + kNonceBytes + kTimeBytes);
    data.insert(data.end(), kCookieLabel.begin(), kCookieLabel.end());
    data.insert(data.end(), from.address.begin(), from.address.end());
    put_le(data, from.port, kPortBytes);
    put_le(data, nonce, kNonceBytes);
    put_le(data, issued_ms, static_cast<int>(kTimeBytes));
    std::array<std::uint8_t, 32> mac{};
    unsigned int length = 0;
    if (HMAC(EVP_sha256(), key.bytes.data(), static_cast<int>(key.bytes.size()), data.data(),
             data.size(), mac.data(), &length) == nullptr ||
        length != mac.size()) {
        throw std::runtime_error("HMAC-SHA256 failed in OpenSSL");
    }
    return mac;
}

} // namespace

ChallengeCookie make_challenge_cookie(const TokenKey& key, const SourceAddress& from,
                                      std::uint64_t nonce, std::uint64_t now_ms) {
    ChallengeCookie cookie{};
    for (std::size_t i = 0; i < kTimeBytes; ++i) {
        cookie[i] = static_cast<std::uint8_t>(now_ms >> (8 * i));
    }
    const auto mac = cookie_mac(key, from, nonce, now_ms);
    std::memcpy(cookie.data() + kTimeBytes, mac.data(), kCookieMacBytes);
    return cookie;
}

CookieStatus check_challenge_cookie(const TokenKey& key, std::span<const std::uint8_t> cookie,
                                    const SourceAddress& from, std::uint64_t nonce,
                                    std::uint64_t now_ms, std::uint64_t max_age_ms) {
    if (cookie.size() != kCookieBytes) {
        return CookieStatus::forged;
    }
    std::uint64_t issued = 0;
    for (std::size_t i = 0; i < kTimeBytes; ++i) {
        issued |= static_cast<std::uint64_t>(cookie[i]) << (8 * i);
    }
    const auto mac = cookie_mac(key, from, nonce, issued);
    if (CRYPTO_memcmp(mac.data(), cookie.data() + kTimeBytes, kCookieMacBytes) != 0) {
        return CookieStatus::forged;
    }
    if (issued > now_ms || now_ms - issued > max_age_ms) {
        return CookieStatus::expired;
    }
    return CookieStatus::valid;
}

std::uint64_t random_nonzero_u64() {
    std::uint64_t v = 0;
    while (v == 0) {
        if (RAND_bytes(reinterpret_cast<unsigned char*>(&v), sizeof v) != 1) {
            throw std::runtime_error("OpenSSL RAND_bytes failed: no random session id");
        }
    }
    return v;
}

} // namespace dsoc::protocol
