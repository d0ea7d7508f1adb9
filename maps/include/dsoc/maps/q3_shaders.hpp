#pragma once
// Quake 3 shader scripts (scripts/*.shader in a game's .pk3 archives), read for one
// question: does a surface drawn with a shader let sight through? The compiled map says
// only what the compiler was told (CONTENTS_TRANSLUCENT for `surfaceparm trans`); an
// alpha-tested grate or a blended window without that parm is marked solid, and a wall
// whose texture name merely sounds see-through is not. The script decides, by the
// renderer's rule (docs/maps.md, "Shader scripts"):
// - see-through: the first stage is alpha-tested (alphaFunc) or blended onto what is
//   behind it (a blendFunc other than GL_ONE GL_ZERO); the shader has no stage (it
//   draws nothing); its vertices move (deformVertexes other than `normal`: the surface
//   need not cover the brush face); it is a portal or mirror; or it is nodraw;
// - opaque: anything else, and a sky (skyparms or surfaceparm sky: the sky box hides
//   what is behind it), whatever its cloud stages blend.
// A name defined more than once is see-through if any definition is (conservative).
//
// Threading: none; a ShaderScripts is read-only once built.

#include "dsoc/maps/load_error.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace dsoc::maps {

/// Longest script read (the largest of OpenArena's is under 200 KiB). [Units: bytes]
inline constexpr std::size_t kMaxShaderScriptBytes = 8u * 1024u * 1024u;

enum class ShaderSight : std::uint8_t { opaque, see_through };

class ShaderScripts {
public:
    /// Adds the definitions of one script's text, named `source` in errors. On malformed
    /// text (a name without its body, an unclosed or stray brace, a stage inside a stage,
    /// text over kMaxShaderScriptBytes) the definitions before the fault are kept, the
    /// rest of the script is not read, the set stops being complete() and the error names
    /// the script, the line and the fault.
    [[nodiscard]] std::optional<LoadError> add(std::string_view text, std::string_view source);
    /// Marks the set incomplete: scripts the game runs with could not be read (an archive
    /// that does not open).
    void mark_incomplete() { complete_ = false; }

    /// How `name` draws, when a script defines it: matched as Quake 3 looks shaders up
    /// (case-insensitively, '\\' as '/', without a file extension such as ".tga").
    [[nodiscard]] std::optional<ShaderSight> sight(std::string_view name) const;
    /// Shaders defined.
    [[nodiscard]] std::size_t size() const { return sight_.size(); }
    /// Scripts added (whole or in part).
    [[nodiscard]] std::size_t scripts() const { return scripts_; }
    /// Every script added was read to its end and no archive failed.
    [[nodiscard]] bool complete() const { return complete_; }

private:
    std::unordered_map<std::string, ShaderSight> sight_; // by lower-case name
    std::size_t scripts_ = 0;
    bool complete_ = true;
};

/// What the scripts of `archives` define (every "scripts/*.shader" entry of each, in
/// the order given), and the problems met: an archive that does not open or a script
/// that does not read whole is named in `problems` and leaves the set incomplete,
/// never a load error (the map still loads, with the conservative rule where the
/// scripts do not answer: docs/maps.md).
struct ShaderScriptsRead {
    ShaderScripts scripts;
    std::vector<LoadError> problems;
};
[[nodiscard]] ShaderScriptsRead
read_shader_scripts(const std::vector<std::filesystem::path>& archives);

/// Whether a drawn side with shader `name` lets sight through: the script's answer
/// when `scripts` define it; when they do not, a shader with no script is drawn opaque
/// by the game (its image, then the lightmap), so opaque - but only when `scripts`
/// hold the game's scripts whole (some, and complete()); without them, a name that
/// sounds see-through (grate, window, glass, fence, ...) counts as see-through.
[[nodiscard]] bool lets_sight_through(std::string_view name, const ShaderScripts* scripts);

} // namespace dsoc::maps
