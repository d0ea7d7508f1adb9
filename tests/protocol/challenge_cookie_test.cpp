#include "dsoc/protocol/challenge_cookie.hpp"

#include <gtest/gtest.h>

#include <set>
#include <vector>

namespace dsoc::protocol {
namespace {

constexpr std::uint64_t kNonce = 0x0123456789abcdefu;
constexpr std::uint64_t kNow = 1'700'000'000'000u; // ms since the epoch
constexpr std::uint64_t kMaxAge = 5'000;

/// 192.0.2.7:27960, as the IPv4-mapped IPv6 address ::ffff:192.0.2.7.
SourceAddress client_address() {
    SourceAddress from;
    from.address[10] = 0xff;
    from.address[11] = 0xff;
    from.address[12] = 192;
    from.address[13] = 0;
    from.address[14] = 2;
    from.address[15] = 7;
    from.port = 27960;
    return from;
}

TEST(ChallengeCookie, IsValidForItsAddressPortAndNonceUntilMaxAge) {
    const TokenKey key = generate_token_key();
    const ChallengeCookie cookie = make_challenge_cookie(key, client_address(), kNonce, kNow);
    for (std::size_t i = 0; i < 8; ++i) { // the issue time comes first, little-endian
        EXPECT_EQ(cookie[i], static_cast<std::uint8_t>(kNow >> (8 * i))) << "byte " << i;
    }
    EXPECT_EQ(check_challenge_cookie(key, cookie, client_address(), kNonce, kNow, kMaxAge),
              CookieStatus::valid);
    EXPECT_EQ(
        check_challenge_cookie(key, cookie, client_address(), kNonce, kNow + kMaxAge, kMaxAge),
        CookieStatus::valid);
    // Deterministic: the server stores nothing, so the same inputs make the same cookie.
    EXPECT_EQ(make_challenge_cookie(key, client_address(), kNonce, kNow), cookie);
}

TEST(ChallengeCookie, AnotherAddressPortNonceIssueTimeOrKeyIsForged) {
    const TokenKey key = generate_token_key();
    const ChallengeCookie cookie = make_challenge_cookie(key, client_address(), kNonce, kNow);
    const auto check = [&](const SourceAddress& from, std::uint64_t nonce) {
        return check_challenge_cookie(key, cookie, from, nonce, kNow, kMaxAge);
    };
    for (std::size_t i = 0; i < 16; ++i) {
        SourceAddress from = client_address();
        from.address[i] ^= 0x01;
        EXPECT_EQ(check(from, kNonce), CookieStatus::forged) << "address byte " << i;
    }
    SourceAddress other_port = client_address();
    other_port.port = 27961;
    EXPECT_EQ(check(other_port, kNonce), CookieStatus::forged);
    other_port.port = static_cast<std::uint16_t>(client_address().port << 8 |
                                                 client_address().port >> 8); // byte order
    EXPECT_EQ(check(other_port, kNonce), CookieStatus::forged);
    other_port.port = static_cast<std::uint16_t>(client_address().port ^ 0x0100); // high byte
    EXPECT_EQ(check(other_port, kNonce), CookieStatus::forged);
    EXPECT_EQ(check(client_address(), kNonce ^ 0x8000000000000000u), CookieStatus::forged);
    EXPECT_EQ(check(client_address(), kNonce + 1), CookieStatus::forged);

    // A client that moves its issue time (to make an old cookie young) breaks the MAC.
    ChallengeCookie younger = cookie;
    younger[0] = static_cast<std::uint8_t>(younger[0] + 1);
    EXPECT_EQ(check_challenge_cookie(key, younger, client_address(), kNonce, kNow + 1, kMaxAge),
              CookieStatus::forged);

    EXPECT_EQ(check_challenge_cookie(generate_token_key(), cookie, client_address(), kNonce, kNow,
                                     kMaxAge),
              CookieStatus::forged);
}

TEST(ChallengeCookie, EveryFlippedBitIsForged) {
    const TokenKey key = generate_token_key();
    const ChallengeCookie cookie = make_challenge_cookie(key, client_address(), kNonce, kNow);
    for (std::size_t bit = 0; bit < 8 * kCookieBytes; ++bit) {
        ChallengeCookie altered = cookie;
        altered[bit / 8] = static_cast<std::uint8_t>(altered[bit / 8] ^ (1u << (bit % 8)));
        // Any age passes: only the MAC can refuse it.
        EXPECT_EQ(
            check_challenge_cookie(key, altered, client_address(), kNonce, kNow, ~std::uint64_t{0}),
            CookieStatus::forged)
            << "bit " << bit;
    }
}

TEST(ChallengeCookie, TooOldOrFromTheFutureIsExpired) {
    const TokenKey key = generate_token_key();
    const ChallengeCookie cookie = make_challenge_cookie(key, client_address(), kNonce, kNow);
    EXPECT_EQ(
        check_challenge_cookie(key, cookie, client_address(), kNonce, kNow + kMaxAge + 1, kMaxAge),
        CookieStatus::expired);
    EXPECT_EQ(
        check_challenge_cookie(key, cookie, client_address(), kNonce, kNow + 3'600'000, kMaxAge),
        CookieStatus::expired);
    EXPECT_EQ(check_challenge_cookie(key, cookie, client_address(), kNonce, kNow - 1, kMaxAge),
              CookieStatus::expired); // issued in the future
    EXPECT_EQ(
        check_challenge_cookie(key, cookie, client_address(), kNonce, kNow - 1, ~std::uint64_t{0}),
        CookieStatus::expired); // however long a cookie may live
    EXPECT_EQ(check_challenge_cookie(key, cookie, client_address(), kNonce, 0, kMaxAge),
              CookieStatus::expired);
    // A forgery is forged whatever its age: the MAC is checked first.
    ChallengeCookie forged = cookie;
    forged[kCookieBytes - 1] ^= 0x80;
    EXPECT_EQ(
        check_challenge_cookie(key, forged, client_address(), kNonce, kNow + kMaxAge + 1, kMaxAge),
        CookieStatus::forged);
}

TEST(ChallengeCookie, TheWrongLengthIsForged) {
    const TokenKey key = generate_token_key();
    const ChallengeCookie cookie = make_challenge_cookie(key, client_address(), kNonce, kNow);
    std::vector<std::uint8_t> bytes(cookie.begin(), cookie.end());
    EXPECT_EQ(check_challenge_cookie(key, bytes, client_address(), kNonce, kNow, kMaxAge),
              CookieStatus::valid);
    EXPECT_EQ(check_challenge_cookie(key, std::span(bytes).first(kCookieBytes - 1),
                                     client_address(), kNonce, kNow, kMaxAge),
              CookieStatus::forged);
    EXPECT_EQ(check_challenge_cookie(key, {}, client_address(), kNonce, kNow, kMaxAge),
              CookieStatus::forged);
    bytes.push_back(0);
    EXPECT_EQ(check_challenge_cookie(key, bytes, client_address(), kNonce, kNow, kMaxAge),
              CookieStatus::forged);
}

TEST(RandomNonzeroU64, IsNeverZeroAndVaries) {
    std::set<std::uint64_t> seen;
    std::uint64_t any_bits = 0;
    for (int i = 0; i < 1000; ++i) {
        const std::uint64_t v = random_nonzero_u64();
        EXPECT_NE(v, 0u);
        seen.insert(v);
        any_bits |= v;
    }
    EXPECT_EQ(seen.size(), 1000u);          // 64 random bits: a repeat in 1,000 is ~2^-45 likely
    EXPECT_EQ(any_bits, ~std::uint64_t{0}); // every bit is sometimes set
}

} // namespace
} // namespace dsoc::protocol
