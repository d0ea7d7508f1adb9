#pragma once
// The compressed form of a table row (internal to the visibility library): each 64-bit
// word of a row is a 2-bit code in a class word (word w at bits 2(w % 32) of class word
// w / 32; 0 all hidden, 1 all visible, 2 a literal), and the literal words follow one
// another in word order. One encoder and one decoder, for the table's rows
// (cell_visibility.cpp) and the unions of blocks of its rows (cell_block_unions.cpp).

#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace dsoc::visibility::row_codes {

enum WordClass : std::uint64_t { kHidden = 0, kVisible = 1, kLiteral = 2 };

/// Class words a row of `words` words takes.
[[nodiscard]] constexpr std::size_t class_words_for(std::size_t words) {
    return (words + 31) / 32;
}

/// The valid bits of word `w` of a row of `bits` bits.
[[nodiscard]] constexpr std::uint64_t full_word(std::size_t bits, std::size_t w) {
    const std::size_t rest = bits - w * 64;
    return rest >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << rest) - 1;
}

/// Bits 0, 2, 4, ..., 62 of `x` as bits 0..31: of a class word's 2-bit codes, the words
/// whose code has its low bit set (`x`) or its high bit (`x >> 1`).
[[nodiscard]] constexpr std::uint32_t even_bits(std::uint64_t x) {
    x &= 0x5555555555555555u;
    x = (x | x >> 1) & 0x3333333333333333u;
    x = (x | x >> 2) & 0x0f0f0f0f0f0f0f0fu;
    x = (x | x >> 4) & 0x00ff00ff00ff00ffu;
    x = (x | x >> 8) & 0x0000ffff0000ffffu;
    x = (x | x >> 16) & 0x00000000ffffffffu;
    return static_cast<std::uint32_t>(x);
}
static_assert(even_bits(0x5u) == 0x3u && even_bits(0xau) == 0x0u && even_bits(0x9u) == 0x1u &&
              even_bits(std::uint64_t{1} << 62) == 0x80000000u);

/// Codes the dense row `row` (the words of a row of `bits` bits, none set past the
/// last) into `classes` (class_words_for() words, all zero on entry) and appends its
/// literals to `literals`.
inline void encode_row(const std::uint64_t* row, std::size_t bits, std::uint64_t* classes,
                       std::vector<std::uint64_t>& literals) {
    const std::size_t words = (bits + 63) / 64;
    for (std::size_t w = 0; w < words; ++w) {
        std::uint64_t code = kHidden;
        if (row[w] == full_word(bits, w)) {
            code = kVisible;
        } else if (row[w] != 0) {
            code = kLiteral;
            literals.push_back(row[w]);
        }
        classes[w >> 5] |= code << (2 * (w & 31));
    }
}

/// ORs a coded row (its `class_words` class words and its first literal) into `out`,
/// where a visible word becomes all ones: the caller clears the last word's bits past
/// the row's last bit. Per class word, its literal words and its visible words as two
/// masks of its 32 words: the literals are ORed in word order (the order they are
/// stored in), each step independent of the codes.
inline void or_coded_row(const std::uint64_t* classes, std::size_t class_words,
                         const std::uint64_t* literal, std::uint64_t* out) {
    for (std::size_t cw = 0; cw < class_words; ++cw) {
        const std::uint64_t codes = classes[cw];
        if (codes == 0) {
            continue; // 32 hidden words
        }
        std::uint64_t* words = out + cw * 32;
        static_assert(kVisible == 1 && kLiteral == 2); // the low bit, the high bit
        for (std::uint32_t literals = even_bits(codes >> 1); literals != 0;
             literals &= literals - 1) {
            words[std::countr_zero(literals)] |= *literal++;
        }
        for (std::uint32_t visible = even_bits(codes); visible != 0; visible &= visible - 1) {
            words[std::countr_zero(visible)] = ~std::uint64_t{0};
        }
    }
}

} // namespace dsoc::visibility::row_codes
