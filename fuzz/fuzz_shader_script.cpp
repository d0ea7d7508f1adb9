// Fuzzes the Quake 3 shader-script reader (ShaderScripts::add): any bytes must give
// definitions or a LoadError, never a crash, a sanitizer report or a hang, and the set
// must keep its promises (q3_shaders.hpp):
// - an error leaves the set not complete(), and no error keeps it complete();
// - sight() ignores case: every word of the input answers as its upper and lower case do;
// - reading the same text again is deterministic (the same error or none, the same
//   shaders) and never turns a see-through shader opaque or forgets a shader;
// - a script read whole, then a shader with no stage on a line of its own, defines that
//   shader as see-through (when no quote or block comment could swallow it).

#include "dsoc/maps/q3_shaders.hpp"

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace {

using dsoc::maps::ShaderScripts;
using dsoc::maps::ShaderSight;

/// Up to 64 distinct words of `text` (runs of bytes between ASCII white space): the
/// names, keywords and braces a reader could have taken for shader names.
std::vector<std::string> words_of(std::string_view text) {
    std::vector<std::string> words;
    std::size_t at = 0;
    while (at < text.size() && words.size() < 64) {
        while (at < text.size() && std::isspace(static_cast<unsigned char>(text[at])) != 0) {
            ++at;
        }
        const std::size_t start = at;
        while (at < text.size() && std::isspace(static_cast<unsigned char>(text[at])) == 0) {
            ++at;
        }
        if (at > start) {
            std::string word(text.substr(start, at - start));
            if (std::find(words.begin(), words.end(), word) == words.end()) {
                words.push_back(std::move(word));
            }
        }
    }
    return words;
}

std::string with_case(std::string_view word, int (*to)(int)) {
    std::string out(word);
    for (char& c : out) {
        c = static_cast<char>(to(static_cast<unsigned char>(c)));
    }
    return out;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);

    ShaderScripts scripts;
    const auto error = scripts.add(text, "fuzz.shader");
    if (error) {
        (void)error->message();
    }
    if (error.has_value() == scripts.complete() || scripts.scripts() != 1) {
        std::abort(); // an error must leave the set incomplete, and only an error may
    }

    const std::vector<std::string> words = words_of(text);
    std::vector<std::optional<ShaderSight>> first;
    for (const std::string& word : words) {
        const auto sight = scripts.sight(word);
        if (sight != scripts.sight(with_case(word, std::toupper)) ||
            sight != scripts.sight(with_case(word, std::tolower))) {
            std::abort(); // names are matched case-insensitively
        }
        first.push_back(sight);
    }

    const std::size_t shaders = scripts.size();
    const auto again = scripts.add(text, "fuzz.shader");
    if (again.has_value() != error.has_value() || (again && again->message() != error->message()) ||
        scripts.size() != shaders || scripts.scripts() != 2) {
        std::abort(); // the same text read again reads the same
    }
    for (std::size_t i = 0; i < words.size(); ++i) {
        const auto sight = scripts.sight(words[i]);
        if (first[i].has_value() != sight.has_value() ||
            (first[i] == ShaderSight::see_through && sight != ShaderSight::see_through)) {
            std::abort(); // a definition read again is still there, see-through stays so
        }
    }

    // A probe after a whole script: nothing but an unclosed quote or /* */ comment can
    // keep the reader from its own line.
    if (!error && text.find('"') == std::string_view::npos &&
        text.find("/*") == std::string_view::npos) {
        ShaderScripts probed;
        std::string probe_text(text);
        probe_text += "\nfuzz/probe_NO_STAGE\n{\n}\n";
        if (probed.add(probe_text, "probe.shader") ||
            probed.sight("FUZZ/probe_no_stage") != ShaderSight::see_through) {
            std::abort(); // a shader with no stage draws nothing: see-through
        }
    }
    return 0;
}
