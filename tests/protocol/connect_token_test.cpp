#include "dsoc/protocol/connect_token.hpp"

#include <gtest/gtest.h>

namespace dsoc::protocol {
namespace {

TEST(ConnectToken, MintedTokenVerifiesWithItsGrant) {
    const TokenKey key = generate_token_key();
    const auto token = mint_connect_token(key, {42, 1'000'100});
    ASSERT_EQ(token.size(), kConnectTokenBytes);
    const auto check = verify_connect_token(key, token, 1'000'000);
    EXPECT_EQ(check.status, TokenStatus::valid) << check.why;
    EXPECT_EQ(check.token.client_id, 42u);
    EXPECT_EQ(check.token.expires_unix_s, 1'000'100u);
}

TEST(ConnectToken, EveryAlteredByteBreaksTheSignature) {
    const TokenKey key = generate_token_key();
    const auto token = mint_connect_token(key, {42, 1'000'100});
    for (std::size_t i = 1; i < token.size(); ++i) { // byte 0 is the version
        auto altered = token;
        altered[i] ^= 0x10;
        const auto check = verify_connect_token(key, altered, 1'000'000);
        EXPECT_EQ(check.status, TokenStatus::bad_signature) << "byte " << i;
    }
}

TEST(ConnectToken, AnotherKeysTokenIsRefused) {
    const auto token = mint_connect_token(generate_token_key(), {42, 1'000'100});
    const auto check = verify_connect_token(generate_token_key(), token, 1'000'000);
    EXPECT_EQ(check.status, TokenStatus::bad_signature);
    EXPECT_EQ(check.token.client_id, 0u); // nothing from an unverified token is trusted
}

TEST(ConnectToken, ExpiresAtItsExpiry) {
    const TokenKey key = generate_token_key();
    const auto token = mint_connect_token(key, {42, 1'000'100});
    EXPECT_EQ(verify_connect_token(key, token, 1'000'099).status, TokenStatus::valid);
    const auto at = verify_connect_token(key, token, 1'000'100);
    EXPECT_EQ(at.status, TokenStatus::expired);
    const auto later = verify_connect_token(key, token, 1'000'112);
    EXPECT_EQ(later.status, TokenStatus::expired);
    EXPECT_NE(later.why.find("expired 12 s ago"), std::string::npos) << later.why;
}

TEST(ConnectToken, MalformedTokensSayWhy) {
    const TokenKey key = generate_token_key();
    EXPECT_EQ(verify_connect_token(key, {}, 0).status, TokenStatus::malformed);
    const std::vector<std::uint8_t> short_token(48, 1);
    const auto s = verify_connect_token(key, short_token, 0);
    EXPECT_EQ(s.status, TokenStatus::malformed);
    EXPECT_NE(s.why.find("48 bytes, expected 49"), std::string::npos) << s.why;
    auto wrong_version = mint_connect_token(key, {1, 100});
    wrong_version[0] = 2;
    EXPECT_EQ(verify_connect_token(key, wrong_version, 0).status, TokenStatus::malformed);
    const auto id_zero = mint_connect_token(key, {0, 100});
    EXPECT_EQ(verify_connect_token(key, id_zero, 0).status, TokenStatus::malformed);
}

TEST(ConnectToken, KeysRoundTripThroughHexAndRefuseBadText) {
    const TokenKey key = generate_token_key();
    const std::string text = format_token_key(key);
    EXPECT_EQ(text.size(), 64u);
    TokenKey read;
    std::string error;
    std::string spaced = " ";
    spaced.append(text, 0, 10).append("\n").append(text, 10).append("\n");
    ASSERT_TRUE(parse_token_key(spaced, read, error)) << error;
    EXPECT_EQ(read.bytes, key.bytes);
    EXPECT_FALSE(parse_token_key(text.substr(0, 62), read, error));
    EXPECT_NE(error.find("64 hex digits, got 62"), std::string::npos) << error;
    EXPECT_FALSE(parse_token_key(text.substr(0, 63) + "g", read, error));
    EXPECT_FALSE(load_token_key("/nonexistent/key", read, error));
    EXPECT_NE(error.find("/nonexistent/key"), std::string::npos) << error;
}

TEST(ConnectToken, TwoKeysDiffer) {
    EXPECT_NE(generate_token_key().bytes, generate_token_key().bytes);
}

} // namespace
} // namespace dsoc::protocol
