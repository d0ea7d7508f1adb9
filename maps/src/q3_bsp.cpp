#include "dsoc/maps/q3_bsp.hpp"

#include "byte_reader.hpp"

#include <algorithm>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>

namespace dsoc::maps::q3 {

using detail::read_f32;
using detail::read_i32;
using detail::read_u32;

namespace {

constexpr std::size_t kHeaderSize = 8 + 8 * kLumpCount;
constexpr std::size_t kShaderSize = 72;
constexpr std::size_t kPlaneSize = 16;
constexpr std::size_t kNodeSize = 36;
constexpr std::size_t kLeafSize = 48;
constexpr std::size_t kIndexSize = 4;
constexpr std::size_t kModelSize = 40;
constexpr std::size_t kBrushSize = 12;
constexpr std::size_t kBrushSideSize = 8;
constexpr std::size_t kSurfaceSize = 104;
constexpr std::size_t kDrawVertSize = 44; // position, st, lightmap st, normal, colour
constexpr std::int32_t kSurfacePatch = 2;

class Parser {
public:
    Parser(std::span<const std::byte> bytes, Q3Bsp& bsp) : bytes_(bytes), bsp_(bsp) {}

    std::optional<LoadError> run();

private:
    LoadError error(Lump lump, std::string what) const {
        return {bsp_.file, lump_label(lump), std::move(what)};
    }
    /// Checks that the lump's length divides by `record_size`; sets `count`.
    std::optional<LoadError> count_records(Lump lump, std::size_t record_size,
                                           std::size_t& count) const;
    std::span<const std::byte> lump_bytes(Lump lump) const {
        const LumpInfo& info = bsp_.lumps[static_cast<int>(lump)];
        return bytes_.subspan(info.offset, info.length);
    }
    /// `first` and `count` must describe a range inside [0, size).
    static bool range_ok(std::int64_t first, std::int64_t count, std::size_t size) {
        return first >= 0 && count >= 0 && first + count <= static_cast<std::int64_t>(size);
    }
    /// The lump's records into `out` (resized to their count after count_records()),
    /// record i read by `read(bytes of record i, i, out[i])`, which returns the first
    /// problem or nothing.
    template <class T, class Read>
    std::optional<LoadError> read_records(Lump lump, std::size_t record_size, std::vector<T>& out,
                                          Read&& read) const {
        std::size_t count = 0;
        if (auto failure = count_records(lump, record_size, count)) {
            return failure;
        }
        const auto data = lump_bytes(lump);
        out.resize(count);
        for (std::size_t i = 0; i < count; ++i) {
            if (auto failure = read(data.subspan(i * record_size, record_size), i, out[i])) {
                return failure;
            }
        }
        return std::nullopt;
    }
    /// "<record> <i>: <what> index <value> out of range (<size> <things>)" unless
    /// 0 <= value < size.
    std::optional<LoadError> check_index(Lump lump, const char* record, std::size_t i,
                                         const char* what, std::int32_t value, std::size_t size,
                                         const char* things) const {
        if (range_ok(value, 1, size)) {
            return std::nullopt;
        }
        return error(lump, record + (" " + std::to_string(i)) + ": " + what + " index " +
                               std::to_string(value) + " out of range (" + std::to_string(size) +
                               " " + things + ")");
    }
    /// "<record> <i>: <what> [<first>, +<count>) out of range (<size>[ <things>])"
    /// unless the range lies inside [0, size).
    std::optional<LoadError> check_range(Lump lump, const char* record, std::size_t i,
                                         const char* what, std::int32_t first, std::int32_t count,
                                         std::size_t size, std::string_view things = {}) const {
        if (range_ok(first, count, size)) {
            return std::nullopt;
        }
        return error(lump, record + (" " + std::to_string(i)) + ": " + what + " [" +
                               std::to_string(first) + ", +" + std::to_string(count) +
                               ") out of range (" + std::to_string(size) +
                               (things.empty() ? "" : " " + std::string(things)) + ")");
    }

    std::optional<LoadError> parse_header();
    std::optional<LoadError> parse_shaders();
    std::optional<LoadError> parse_planes();
    std::optional<LoadError> parse_brushes();
    std::optional<LoadError> parse_models();
    std::optional<LoadError> parse_tree();
    std::optional<LoadError> parse_surfaces();
    std::optional<LoadError> parse_visibility();

    std::span<const std::byte> bytes_;
    Q3Bsp& bsp_;
};

std::optional<LoadError> Parser::run() {
    for (auto step : {&Parser::parse_header, &Parser::parse_shaders, &Parser::parse_planes,
                      &Parser::parse_brushes, &Parser::parse_surfaces, &Parser::parse_models,
                      &Parser::parse_visibility, &Parser::parse_tree}) {
        if (auto failure = (this->*step)()) {
            return failure;
        }
    }
    return std::nullopt;
}

std::optional<LoadError> Parser::parse_header() {
    if (bytes_.size() < kHeaderSize) {
        std::ostringstream what;
        what << "file is " << bytes_.size() << " bytes, shorter than the " << kHeaderSize
             << "-byte IBSP header";
        return LoadError{bsp_.file, "header", what.str()};
    }
    const char magic[4] = {static_cast<char>(bytes_[0]), static_cast<char>(bytes_[1]),
                           static_cast<char>(bytes_[2]), static_cast<char>(bytes_[3])};
    if (std::string_view(magic, 4) != "IBSP") {
        return LoadError{bsp_.file, "header", "wrong magic (expected \"IBSP\", a Quake 3 BSP)"};
    }
    const std::int32_t version = read_i32(bytes_, 4);
    if (version != kBspVersion) {
        return LoadError{bsp_.file, "header",
                         "unsupported BSP version " + std::to_string(version) +
                             " (expected 46, Quake 3 / OpenArena)"};
    }
    for (int i = 0; i < kLumpCount; ++i) {
        LumpInfo& info = bsp_.lumps[static_cast<std::size_t>(i)];
        const std::int32_t offset = read_i32(bytes_, 8 + 8 * static_cast<std::size_t>(i));
        const std::int32_t length = read_i32(bytes_, 12 + 8 * static_cast<std::size_t>(i));
        const auto lump = static_cast<Lump>(i);
        if (offset < 0 || length < 0) {
            return error(lump, "negative offset " + std::to_string(offset) + " or length " +
                                   std::to_string(length));
        }
        const auto end = static_cast<std::uint64_t>(offset) + static_cast<std::uint64_t>(length);
        if (end > bytes_.size()) {
            return error(lump, "offset " + std::to_string(offset) + " + length " +
                                   std::to_string(length) + " is past the end of the file (" +
                                   std::to_string(bytes_.size()) + " bytes)");
        }
        info.offset = static_cast<std::uint32_t>(offset);
        info.length = static_cast<std::uint32_t>(length);
    }
    // Entities: text, possibly NUL-terminated.
    const auto text = lump_bytes(Lump::entities);
    bsp_.entities.assign(reinterpret_cast<const char*>(text.data()), text.size());
    const auto nul = bsp_.entities.find('\0');
    if (nul != std::string::npos) {
        bsp_.entities.resize(nul);
    }
    return std::nullopt;
}

std::optional<LoadError> Parser::count_records(Lump lump, std::size_t record_size,
                                               std::size_t& count) const {
    const std::size_t length = bsp_.lumps[static_cast<int>(lump)].length;
    if (length % record_size != 0) {
        return error(lump, "length " + std::to_string(length) + " is not a multiple of the " +
                               std::to_string(record_size) + "-byte record size");
    }
    count = length / record_size;
    return std::nullopt;
}

std::optional<LoadError> Parser::parse_shaders() {
    return read_records(Lump::shaders, kShaderSize, bsp_.shaders,
                        [](std::span<const std::byte> r, std::size_t, Shader& shader) {
                            const char* name = reinterpret_cast<const char*>(r.data());
                            std::size_t length = 0;
                            while (length < 64 && name[length] != '\0') {
                                ++length;
                            }
                            shader.name.assign(name, length);
                            shader.surface_flags = read_u32(r, 64);
                            shader.content_flags = read_u32(r, 68);
                            return std::optional<LoadError>();
                        });
}

std::optional<LoadError> Parser::parse_planes() {
    return read_records(Lump::planes, kPlaneSize, bsp_.planes,
                        [](std::span<const std::byte> r, std::size_t, Plane& plane) {
                            plane.normal = {read_f32(r, 0), read_f32(r, 4), read_f32(r, 8)};
                            plane.dist = read_f32(r, 12);
                            return std::optional<LoadError>();
                        });
}

std::optional<LoadError> Parser::parse_brushes() {
    if (auto failure =
            read_records(Lump::brush_sides, kBrushSideSize, bsp_.brush_sides,
                         [&](std::span<const std::byte> r, std::size_t i, BrushSide& side) {
                             side.plane = read_i32(r, 0);
                             side.shader = read_i32(r, 4);
                             if (auto bad = check_index(Lump::brush_sides, "side", i, "plane",
                                                        side.plane, bsp_.planes.size(), "planes")) {
                                 return bad;
                             }
                             return check_index(Lump::brush_sides, "side", i, "shader", side.shader,
                                                bsp_.shaders.size(), "shaders");
                         })) {
        return failure;
    }
    return read_records(Lump::brushes, kBrushSize, bsp_.brushes,
                        [&](std::span<const std::byte> r, std::size_t i, Brush& brush) {
                            brush.first_side = read_i32(r, 0);
                            brush.num_sides = read_i32(r, 4);
                            brush.shader = read_i32(r, 8);
                            if (auto bad = check_range(Lump::brushes, "brush", i, "sides",
                                                       brush.first_side, brush.num_sides,
                                                       bsp_.brush_sides.size(), "brush sides")) {
                                return bad;
                            }
                            return check_index(Lump::brushes, "brush", i, "shader", brush.shader,
                                               bsp_.shaders.size(), "shaders");
                        });
}

std::optional<LoadError> Parser::parse_surfaces() {
    std::size_t count = 0;
    if (auto failure = count_records(Lump::surfaces, kSurfaceSize, count)) {
        return failure;
    }
    std::size_t vert_count = 0;
    if (auto failure = count_records(Lump::draw_verts, kDrawVertSize, vert_count)) {
        return failure;
    }
    const auto data = lump_bytes(Lump::surfaces);
    const auto verts = lump_bytes(Lump::draw_verts);
    bsp_.surface_count = static_cast<std::uint32_t>(count);
    std::size_t patch_points = 0; // bounded by vert_count: memory bounded by the input
    for (std::size_t i = 0; i < count; ++i) {
        const auto record = data.subspan(i * kSurfaceSize, kSurfaceSize);
        if (read_i32(record, 8) != kSurfacePatch) {
            continue;
        }
        ++bsp_.patch_surface_count;
        Patch patch;
        patch.surface = static_cast<std::int32_t>(i);
        patch.shader = read_i32(record, 0);
        const std::int32_t first_vert = read_i32(record, 12);
        const std::int32_t num_verts = read_i32(record, 16);
        patch.width = read_i32(record, 96);
        patch.height = read_i32(record, 100);
        if (auto bad = check_index(Lump::surfaces, "surface", i, "shader", patch.shader,
                                   bsp_.shaders.size(), "shaders")) {
            return bad;
        }
        if (auto bad = check_range(Lump::surfaces, "surface", i, "vertices", first_vert, num_verts,
                                   vert_count, "draw vertices")) {
            return bad;
        }
        const auto side_ok = [](std::int32_t n) {
            return n >= 3 && n <= kMaxPatchSide && n % 2 == 1;
        };
        if (!side_ok(patch.width) || !side_ok(patch.height) ||
            static_cast<std::int64_t>(patch.width) * patch.height != num_verts) {
            return error(Lump::surfaces,
                         "surface " + std::to_string(i) + ": patch of " +
                             std::to_string(patch.width) + " x " + std::to_string(patch.height) +
                             " control points with " + std::to_string(num_verts) +
                             " vertices (each side odd, 3 to " + std::to_string(kMaxPatchSide) +
                             ", and width x height vertices)");
        }
        patch_points += static_cast<std::size_t>(num_verts);
        if (patch_points > vert_count) {
            return error(Lump::surfaces,
                         "surface " + std::to_string(i) + ": the patches so far hold " +
                             std::to_string(patch_points) + " control points, more than the " +
                             std::to_string(vert_count) +
                             " draw vertices (patches share vertices)");
        }
        patch.points.reserve(static_cast<std::size_t>(num_verts));
        for (std::int32_t v = 0; v < num_verts; ++v) {
            const auto vert = verts.subspan(
                static_cast<std::size_t>(first_vert + v) * kDrawVertSize, kDrawVertSize);
            patch.points.emplace_back(read_f32(vert, 0), read_f32(vert, 4), read_f32(vert, 8));
        }
        bsp_.patches.push_back(std::move(patch));
    }
    std::size_t leaf_surfaces = 0;
    if (auto failure = count_records(Lump::leaf_surfaces, kIndexSize, leaf_surfaces)) {
        return failure;
    }
    bsp_.leaf_surface_count = static_cast<std::uint32_t>(leaf_surfaces);
    return std::nullopt;
}

std::optional<LoadError> Parser::parse_models() {
    std::size_t count = 0;
    if (auto failure = count_records(Lump::models, kModelSize, count)) {
        return failure;
    }
    if (count == 0) {
        return error(Lump::models, "no models (model 0, the world, is required)");
    }
    return read_records(
        Lump::models, kModelSize, bsp_.models,
        [&](std::span<const std::byte> r, std::size_t i, Model& model) {
            model.mins = {read_f32(r, 0), read_f32(r, 4), read_f32(r, 8)};
            model.maxs = {read_f32(r, 12), read_f32(r, 16), read_f32(r, 20)};
            model.first_surface = read_i32(r, 24);
            model.num_surfaces = read_i32(r, 28);
            model.first_brush = read_i32(r, 32);
            model.num_brushes = read_i32(r, 36);
            if (auto bad = check_range(Lump::models, "model", i, "brushes", model.first_brush,
                                       model.num_brushes, bsp_.brushes.size(), "brushes")) {
                return bad;
            }
            return check_range(Lump::models, "model", i, "surfaces", model.first_surface,
                               model.num_surfaces, bsp_.surface_count, "surfaces");
        });
}

std::optional<LoadError> Parser::parse_visibility() {
    const auto data = lump_bytes(Lump::visibility);
    if (data.empty()) {
        return std::nullopt; // compiled without vis: everything potentially visible
    }
    if (data.size() < 8) {
        return error(Lump::visibility, "length " + std::to_string(data.size()) +
                                           " is shorter than its 8-byte header");
    }
    const std::int32_t clusters = read_i32(data, 0);
    const std::int32_t row_bytes = read_i32(data, 4);
    if (clusters < 0 || row_bytes < 0) {
        return error(Lump::visibility, "negative cluster count " + std::to_string(clusters) +
                                           " or row size " + std::to_string(row_bytes));
    }
    const auto needed =
        static_cast<std::uint64_t>(clusters) * static_cast<std::uint64_t>(row_bytes);
    if (needed > data.size() - 8) {
        return error(Lump::visibility, std::to_string(clusters) + " clusters x " +
                                           std::to_string(row_bytes) + " bytes need " +
                                           std::to_string(needed) + " bytes, lump has " +
                                           std::to_string(data.size() - 8));
    }
    if (static_cast<std::uint64_t>(row_bytes) * 8 < static_cast<std::uint64_t>(clusters)) {
        return error(Lump::visibility, "row of " + std::to_string(row_bytes) +
                                           " bytes cannot hold " + std::to_string(clusters) +
                                           " cluster bits");
    }
    bsp_.visibility.num_clusters = clusters;
    bsp_.visibility.bytes_per_cluster = row_bytes;
    bsp_.visibility.bits.resize(static_cast<std::size_t>(needed));
    for (std::size_t i = 0; i < needed; ++i) {
        bsp_.visibility.bits[i] = static_cast<std::uint8_t>(data[8 + i]);
    }
    return std::nullopt;
}

std::optional<LoadError> Parser::parse_tree() {
    if (auto failure =
            read_records(Lump::leaf_brushes, kIndexSize, bsp_.leaf_brushes,
                         [&](std::span<const std::byte> r, std::size_t i, std::int32_t& brush) {
                             brush = read_i32(r, 0);
                             return check_index(Lump::leaf_brushes, "entry", i, "brush", brush,
                                                bsp_.brushes.size(), "brushes");
                         })) {
        return failure;
    }
    const std::int32_t clusters = bsp_.visibility.num_clusters;
    if (auto failure = read_records(
            Lump::leafs, kLeafSize, bsp_.leafs,
            [&](std::span<const std::byte> r, std::size_t i, Leaf& leaf) {
                leaf.cluster = read_i32(r, 0);
                leaf.area = read_i32(r, 4);
                for (std::size_t a = 0; a < 3; ++a) {
                    leaf.mins[a] = read_i32(r, 8 + 4 * a);
                    leaf.maxs[a] = read_i32(r, 20 + 4 * a);
                }
                leaf.first_leaf_surface = read_i32(r, 32);
                leaf.num_leaf_surfaces = read_i32(r, 36);
                leaf.first_leaf_brush = read_i32(r, 40);
                leaf.num_leaf_brushes = read_i32(r, 44);
                if (leaf.cluster < -1 || (clusters > 0 && leaf.cluster >= clusters)) {
                    return std::optional(
                        error(Lump::leafs, "leaf " + std::to_string(i) + ": cluster " +
                                               std::to_string(leaf.cluster) + " out of range (" +
                                               std::to_string(clusters) +
                                               " clusters in the visibility lump)"));
                }
                if (auto bad =
                        check_range(Lump::leafs, "leaf", i, "leaf brushes", leaf.first_leaf_brush,
                                    leaf.num_leaf_brushes, bsp_.leaf_brushes.size())) {
                    return bad;
                }
                return check_range(Lump::leafs, "leaf", i, "leaf surfaces", leaf.first_leaf_surface,
                                   leaf.num_leaf_surfaces, bsp_.leaf_surface_count);
            })) {
        return failure;
    }
    std::size_t node_count = 0;
    if (auto failure = count_records(Lump::nodes, kNodeSize, node_count)) {
        return failure;
    }
    const std::size_t leaf_count = bsp_.leafs.size();
    return read_records(
        Lump::nodes, kNodeSize, bsp_.nodes,
        [&](std::span<const std::byte> r, std::size_t i, Node& node) -> std::optional<LoadError> {
            node.plane = read_i32(r, 0);
            node.children = {read_i32(r, 4), read_i32(r, 8)};
            for (std::size_t a = 0; a < 3; ++a) {
                node.mins[a] = read_i32(r, 12 + 4 * a);
                node.maxs[a] = read_i32(r, 24 + 4 * a);
            }
            if (auto bad = check_index(Lump::nodes, "node", i, "plane", node.plane,
                                       bsp_.planes.size(), "planes")) {
                return bad;
            }
            for (const std::int32_t child : node.children) {
                // Nodes only point forward in a well-formed tree, so a walk always ends;
                // requiring child > i rules out cycles in hostile input.
                const std::int64_t leaf = -(static_cast<std::int64_t>(child) + 1);
                const bool ok = child >= 0 ? (static_cast<std::size_t>(child) < node_count &&
                                              static_cast<std::size_t>(child) > i)
                                           : leaf < static_cast<std::int64_t>(leaf_count);
                if (!ok) {
                    return error(Lump::nodes, "node " + std::to_string(i) + ": child " +
                                                  std::to_string(child) +
                                                  " out of range or not after its parent (" +
                                                  std::to_string(node_count) + " nodes, " +
                                                  std::to_string(leaf_count) + " leafs)");
                }
            }
            return std::nullopt;
        });
}

} // namespace

const char* lump_label(Lump lump) noexcept {
    switch (lump) {
    case Lump::entities:
        return "entities (lump 0)";
    case Lump::shaders:
        return "shaders (lump 1)";
    case Lump::planes:
        return "planes (lump 2)";
    case Lump::nodes:
        return "nodes (lump 3)";
    case Lump::leafs:
        return "leafs (lump 4)";
    case Lump::leaf_surfaces:
        return "leaf surfaces (lump 5)";
    case Lump::leaf_brushes:
        return "leaf brushes (lump 6)";
    case Lump::models:
        return "models (lump 7)";
    case Lump::brushes:
        return "brushes (lump 8)";
    case Lump::brush_sides:
        return "brush sides (lump 9)";
    case Lump::draw_verts:
        return "draw vertexes (lump 10)";
    case Lump::draw_indexes:
        return "draw indexes (lump 11)";
    case Lump::fogs:
        return "fogs (lump 12)";
    case Lump::surfaces:
        return "surfaces (lump 13)";
    case Lump::lightmaps:
        return "lightmaps (lump 14)";
    case Lump::light_grid:
        return "light grid (lump 15)";
    case Lump::visibility:
        return "visibility (lump 16)";
    }
    return "unknown lump";
}

std::span<const std::byte> Q3Bsp::raw_lump(Lump lump) const {
    const LumpInfo& info = lumps[static_cast<int>(lump)];
    return std::span<const std::byte>(bytes).subspan(info.offset, info.length);
}

std::span<const BrushSide> Q3Bsp::sides_of(const Brush& brush) const {
    return std::span<const BrushSide>(brush_sides)
        .subspan(static_cast<std::size_t>(brush.first_side),
                 static_cast<std::size_t>(brush.num_sides));
}

Result<Q3Bsp> parse_q3_bsp(std::span<const std::byte> bytes, std::string file) {
    Q3Bsp bsp;
    bsp.file = std::move(file);
    Parser parser(bytes, bsp);
    if (auto failure = parser.run()) {
        return std::move(*failure);
    }
    bsp.bytes.assign(bytes.begin(), bytes.end());
    return bsp;
}

Result<Q3Bsp> read_q3_bsp_file(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        return LoadError{path.string(), "", "cannot open file"};
    }
    std::vector<char> buffer((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
    if (in.bad()) {
        return LoadError{path.string(), "", "read error"};
    }
    const auto* begin = reinterpret_cast<const std::byte*>(buffer.data());
    return parse_q3_bsp(std::span<const std::byte>(begin, buffer.size()), path.string());
}

} // namespace dsoc::maps::q3
