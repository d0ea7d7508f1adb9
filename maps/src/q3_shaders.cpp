#include "dsoc/maps/q3_shaders.hpp"

#include "dsoc/maps/pk3.hpp"

#include <algorithm>
#include <array>
#include <cctype>

namespace dsoc::maps {

namespace {

std::string lower(std::string_view text) {
    std::string out(text);
    for (char& c : out) {
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    return out;
}

/// Blank as Quake 3's parser has it: every byte up to the space (control bytes, a DOS
/// end-of-file mark, NUL).
bool is_space(char c) {
    return static_cast<unsigned char>(c) <= ' ';
}

/// A shader name as Quake 3 looks it up: lower case, '\\' read as '/', without a file
/// extension (R_FindShader strips ".tga" and the like from the name it is given).
std::string shader_key(std::string_view name) {
    std::string key = lower(name);
    std::replace(key.begin(), key.end(), '\\', '/');
    if (const std::size_t dot = key.rfind('.');
        dot != std::string::npos && key.find('/', dot) == std::string::npos) {
        key.resize(dot);
    }
    return key;
}

/// Quake 3's script tokens (COM_ParseExt): words between white space, "//" and "/* */"
/// comments skipped, a quoted string one token; each with its line.
class Tokens {
public:
    explicit Tokens(std::string_view text) : text_(text) {}

    struct Token {
        std::string_view text;
        std::size_t line = 0;
    };

    /// The next token, or nothing at the end.
    std::optional<Token> next() {
        skip_blank();
        if (at_ >= text_.size()) {
            return std::nullopt;
        }
        const std::size_t line = line_;
        if (text_[at_] == '"') {
            const std::size_t start = ++at_;
            while (at_ < text_.size() && text_[at_] != '"') {
                line_ += text_[at_] == '\n' ? 1 : 0;
                ++at_;
            }
            const std::string_view word = text_.substr(start, at_ - start);
            at_ = std::min(at_ + 1, text_.size()); // the closing quote, when there is one
            return Token{word, line};
        }
        const std::size_t start = at_;
        while (at_ < text_.size() && !is_space(text_[at_])) {
            ++at_;
        }
        return Token{text_.substr(start, at_ - start), line};
    }

    /// The next token when it is on `line` and is not a brace (a keyword's argument).
    std::optional<std::string_view> argument_on(std::size_t line) {
        const std::size_t at = at_;
        const std::size_t line_before = line_;
        if (auto token = next();
            token && token->line == line && token->text != "{" && token->text != "}") {
            return token->text;
        }
        at_ = at; // not an argument: read again as what it is
        line_ = line_before;
        return std::nullopt;
    }

private:
    void skip_blank() {
        while (at_ < text_.size()) {
            const char c = text_[at_];
            if (is_space(c)) {
                line_ += c == '\n' ? 1 : 0;
                ++at_;
            } else if (text_.substr(at_, 2) == "//") {
                while (at_ < text_.size() && text_[at_] != '\n') {
                    ++at_;
                }
            } else if (text_.substr(at_, 2) == "/*") {
                const std::size_t end = text_.find("*/", at_ + 2);
                const std::size_t stop = end == std::string_view::npos ? text_.size() : end + 2;
                line_ += static_cast<std::size_t>(
                    std::count(text_.begin() + static_cast<std::ptrdiff_t>(at_),
                               text_.begin() + static_cast<std::ptrdiff_t>(stop), '\n'));
                at_ = stop;
            } else {
                return;
            }
        }
    }

    std::string_view text_;
    std::size_t at_ = 0;
    std::size_t line_ = 1;
};

/// "shader 'NAME': WHAT" (built by appending: GCC 12 warns falsely on a chain of +).
std::string about(std::string_view name, std::string_view what) {
    std::string text = "shader '";
    text += name;
    text += "': ";
    text += what;
    return text;
}

/// What one shader's body says about sight (the header's rule).
struct SightClues {
    bool sky = false;
    bool nodraw = false;
    bool moves = false;
    bool portal = false;
    std::size_t stages = 0;
    bool first_stage_lets_through = false;

    [[nodiscard]] ShaderSight sight() const {
        if (sky) {
            return ShaderSight::opaque;
        }
        const bool through = nodraw || moves || portal || stages == 0 || first_stage_lets_through;
        return through ? ShaderSight::see_through : ShaderSight::opaque;
    }
};

/// Whether a first stage's blendFunc lets what is behind show: every mode but replace
/// (GL_ONE GL_ZERO). `first` and `second` lower-case; `second` empty for the one-word
/// forms (add, filter, blend).
bool blend_lets_through(std::string_view first, std::string_view second) {
    return !(first == "gl_one" && second == "gl_zero");
}

} // namespace

std::optional<LoadError> ShaderScripts::add(std::string_view text, std::string_view source) {
    ++scripts_;
    const auto fault = [&](std::size_t line, std::string what) {
        complete_ = false;
        return LoadError{std::string(source), line == 0 ? "" : "line " + std::to_string(line),
                         std::move(what)};
    };
    if (text.size() > kMaxShaderScriptBytes) {
        return fault(0, "script of " + std::to_string(text.size()) + " bytes, over the " +
                            std::to_string(kMaxShaderScriptBytes) + " read");
    }
    Tokens tokens(text);
    while (auto name = tokens.next()) {
        if (name->text == "{" || name->text == "}") {
            std::string what = "'";
            what += name->text;
            what += "' where a shader name belongs";
            return fault(name->line, std::move(what));
        }
        const auto open = tokens.next();
        if (!open || open->text != "{") {
            return fault(name->line, about(name->text, "no body ('{' expected after its name)"));
        }
        SightClues clues;
        bool in_stage = false;
        bool closed = false;
        while (auto token = tokens.next()) {
            if (token->text == "{") {
                if (in_stage) {
                    return fault(token->line, about(name->text, "a stage inside a stage"));
                }
                in_stage = true;
                ++clues.stages;
                continue;
            }
            if (token->text == "}") {
                if (!in_stage) {
                    closed = true;
                    break;
                }
                in_stage = false;
                continue;
            }
            const std::string keyword = lower(token->text);
            const std::size_t line = token->line;
            const auto argument = [&] { return lower(tokens.argument_on(line).value_or("")); };
            if (in_stage) {
                if (clues.stages != 1) {
                    continue; // a later stage draws over the first: the first decides
                }
                if (keyword == "alphafunc") {
                    clues.first_stage_lets_through = true;
                } else if (keyword == "blendfunc") {
                    const std::string first = argument();
                    const bool one_word = first == "add" || first == "filter" || first == "blend";
                    const std::string second = one_word ? "" : argument();
                    clues.first_stage_lets_through =
                        clues.first_stage_lets_through || blend_lets_through(first, second);
                }
                continue;
            }
            if (keyword == "surfaceparm") {
                const std::string parm = argument();
                clues.sky = clues.sky || parm == "sky";
                clues.nodraw = clues.nodraw || parm == "nodraw";
            } else if (keyword == "skyparms") {
                clues.sky = true;
            } else if (keyword == "deformvertexes") {
                clues.moves = clues.moves || argument() != "normal";
            } else if (keyword == "portal") {
                clues.portal = true;
            }
        }
        if (!closed) {
            return fault(name->line, about(name->text, "not closed ('}' expected before the end)"));
        }
        const auto [it, fresh] = sight_.try_emplace(shader_key(name->text), clues.sight());
        if (!fresh && clues.sight() == ShaderSight::see_through) {
            it->second = ShaderSight::see_through; // see-through if any definition is
        }
    }
    return std::nullopt;
}

std::optional<ShaderSight> ShaderScripts::sight(std::string_view name) const {
    const auto it = sight_.find(shader_key(name));
    if (it == sight_.end()) {
        return std::nullopt;
    }
    return it->second;
}

ShaderScriptsRead read_shader_scripts(const std::vector<std::filesystem::path>& archives) {
    ShaderScriptsRead read;
    for (const std::filesystem::path& archive : archives) {
        auto entries = read_pk3_entries_in(archive, "scripts/", ".shader");
        if (!entries) {
            read.problems.push_back(entries.error());
            read.scripts.mark_incomplete();
            continue;
        }
        for (const Pk3EntryRead& entry : entries.value()) {
            if (!entry.bytes) {
                read.problems.push_back(entry.bytes.error());
                read.scripts.mark_incomplete();
                continue;
            }
            const std::vector<std::byte>& bytes = entry.bytes.value();
            const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
            if (auto problem = read.scripts.add(text, archive.string() + ":" + entry.name)) {
                read.problems.push_back(std::move(*problem));
            }
        }
    }
    return read;
}

bool lets_sight_through(std::string_view name, const ShaderScripts* scripts) {
    if (scripts != nullptr) {
        if (const auto sight = scripts->sight(name)) {
            return *sight == ShaderSight::see_through;
        }
        if (scripts->size() > 0 && scripts->complete()) {
            return false; // no script: the game draws the image, opaque
        }
    }
    // Without the game's scripts: what a name suggests (conservative: it only culls less).
    static constexpr std::array<std::string_view, 13> kHints = {
        "grate", "window", "glass", "fence", "mesh",  "chain",  "cage",
        "web",   "trans",  "alpha", "net",   "grill", "lattice"};
    const std::string lowered = lower(name);
    return std::any_of(kHints.begin(), kHints.end(), [&](std::string_view hint) {
        return lowered.find(hint) != std::string::npos;
    });
}

} // namespace dsoc::maps
