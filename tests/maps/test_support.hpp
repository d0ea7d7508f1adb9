#pragma once
// Shared helpers for the maps tests: a corridor map, where the OpenArena maps are
// (support/openarena.hpp), and a small in-memory Quake 3 BSP writer for building valid
// and corrupt files.

#include "dsoc/maps/map.hpp"
#include "dsoc/maps/q3_bsp.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"
#include "support/openarena.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace dsoc::maps::test {

/// A small world with no files: the 2 x 2 rooms of visibility::make_corridor_world as a
/// Map (occluders and bounds; no PVS).
inline Map corridor_map(std::uint32_t seed = 3) {
    const visibility::TestWorld w = visibility::make_corridor_world(seed, 2, 2);
    Map map;
    map.name = "corridor";
    map.source = "generator:corridor";
    map.occluders = w.world.occluders();
    map.bounds = w.world.bounds();
    return map;
}

/// corridor_map() and its occluder scene, built once for the whole test program.
struct Corridor {
    Map map;
    std::shared_ptr<const visibility::OccluderScene> scene;
};
inline const Corridor& shared_corridor() {
    static const Corridor c = [] {
        Corridor out{corridor_map(), nullptr};
        out.scene = visibility::OccluderScene::build(out.map.occluders);
        return out;
    }();
    return c;
}

using ::dsoc::testing::kOpenArenaPak;

/// Lumps as raw byte strings; build() lays them out after the header.
struct BspWriter {
    std::array<std::vector<std::byte>, q3::kLumpCount> lumps;
    std::string magic = "IBSP";
    std::int32_t version = 46;

    template <class T>
    void put(q3::Lump lump, const T& value) {
        auto& bytes = lumps[static_cast<std::size_t>(lump)];
        const auto* raw = reinterpret_cast<const std::byte*>(&value);
        bytes.insert(bytes.end(), raw, raw + sizeof(T));
    }
    void put_i32s(q3::Lump lump, std::initializer_list<std::int32_t> values) {
        for (const std::int32_t v : values) {
            put(lump, v);
        }
    }
    void put_f32s(q3::Lump lump, std::initializer_list<float> values) {
        for (const float v : values) {
            put(lump, v);
        }
    }
    void put_shader(const std::string& name, std::uint32_t surface, std::uint32_t contents) {
        std::array<char, 64> raw{};
        std::memcpy(raw.data(), name.data(), std::min<std::size_t>(name.size(), 63));
        auto& bytes = lumps[static_cast<std::size_t>(q3::Lump::shaders)];
        const auto* p = reinterpret_cast<const std::byte*>(raw.data());
        bytes.insert(bytes.end(), p, p + 64);
        put(q3::Lump::shaders, surface);
        put(q3::Lump::shaders, contents);
    }
    /// An axis-aligned box brush using `shader` on every side.
    void put_box_brush(glm::vec3 min, glm::vec3 max, std::int32_t shader) {
        const auto plane_base = static_cast<std::int32_t>(
            lumps[static_cast<std::size_t>(q3::Lump::planes)].size() / 16);
        const auto side_base = static_cast<std::int32_t>(
            lumps[static_cast<std::size_t>(q3::Lump::brush_sides)].size() / 8);
        put_f32s(q3::Lump::planes, {1, 0,  0, max.x,  -1, 0, 0, -min.x, 0, 1, 0,  max.y,
                                    0, -1, 0, -min.y, 0,  0, 1, max.z,  0, 0, -1, -min.z});
        for (std::int32_t i = 0; i < 6; ++i) {
            put_i32s(q3::Lump::brush_sides, {plane_base + i, shader});
        }
        put_i32s(q3::Lump::brushes, {side_base, 6, shader});
    }
    std::vector<std::byte> build() const {
        std::vector<std::byte> out(8 + 8 * q3::kLumpCount);
        std::memcpy(out.data(), magic.data(), std::min<std::size_t>(4, magic.size()));
        std::memcpy(out.data() + 4, &version, 4);
        for (int i = 0; i < q3::kLumpCount; ++i) {
            const auto& lump = lumps[static_cast<std::size_t>(i)];
            const auto offset = static_cast<std::int32_t>(out.size());
            const auto length = static_cast<std::int32_t>(lump.size());
            std::memcpy(out.data() + 8 + 8 * i, &offset, 4);
            std::memcpy(out.data() + 12 + 8 * i, &length, 4);
            out.insert(out.end(), lump.begin(), lump.end());
        }
        return out;
    }
};

/// A valid little map: a floor (solid), a glass pane, a caulk block, a clip brush,
/// one spawn point; model 0 holds all four brushes.
inline BspWriter small_map_writer() {
    BspWriter w;
    const std::string entities = "{\n\"classname\" \"worldspawn\"\n}\n{\n\"classname\" "
                                 "\"info_player_deathmatch\"\n\"origin\" \"0 0 40\"\n\"angle\" "
                                 "\"90\"\n}\n";
    for (const char c : entities) {
        w.put(q3::Lump::entities, c);
    }
    w.put(q3::Lump::entities, '\0');
    w.put_shader("textures/floor", 0, q3::kContentsSolid);
    w.put_shader("textures/glass", 0, q3::kContentsSolid | q3::kContentsTranslucent);
    w.put_shader("textures/common/caulk", q3::kSurfNoDraw, q3::kContentsSolid);
    w.put_shader("textures/common/clip", q3::kSurfNoDraw, q3::kContentsPlayerClip);
    w.put_box_brush({-256, -256, -16}, {256, 256, 0}, 0);
    w.put_box_brush({100, -64, 0}, {104, 64, 128}, 1);
    w.put_box_brush({-200, -200, 0}, {-150, -150, 64}, 2);
    w.put_box_brush({-10, 150, 0}, {10, 200, 256}, 3);
    w.put_f32s(q3::Lump::models, {-256, -256, -16, 256, 256, 256});
    w.put_i32s(q3::Lump::models, {0, 0, 0, 4});
    return w;
}

} // namespace dsoc::maps::test
