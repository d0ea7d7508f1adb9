#include "dsoc/maps/q3_map.hpp"

#include "brush_builder.hpp"
#include "dsoc/maps/entities.hpp"
#include "dsoc/maps/pk3.hpp"
#include "dsoc/maps/q3_shaders.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

namespace dsoc::maps {

Result<Map> map_from_q3_bsp(const q3::Q3Bsp& bsp, std::string name, const ShaderScripts* scripts) {
    Map map;
    map.name = std::move(name);
    map.source = bsp.file;
    map.stats.brushes_total = bsp.brushes.size();
    map.stats.patches_left_out = bsp.patch_surface_count;
    map.stats.shader_scripts =
        scripts != nullptr && scripts->complete() && scripts->size() > 0 ? scripts->scripts() : 0;

    const q3::Model& world = bsp.models.front(); // parse_q3_bsp guarantees one model
    map.stats.world_brushes = static_cast<std::size_t>(world.num_brushes);
    std::vector<visibility::Plane> planes;
    for (std::int32_t b = 0; b < world.num_brushes; ++b) {
        const q3::Brush& brush = bsp.brushes[static_cast<std::size_t>(world.first_brush + b)];
        const std::uint32_t contents =
            bsp.shaders[static_cast<std::size_t>(brush.shader)].content_flags;
        if ((contents & q3::kContentsLava) != 0) {
            visibility::PolyhedronResult result;
            planes.clear();
            for (const q3::BrushSide& side : bsp.sides_of(brush)) {
                const q3::Plane& plane = bsp.planes[static_cast<std::size_t>(side.plane)];
                planes.push_back({plane.normal, plane.dist});
            }
            if (planes.size() > kMaxBrushPlanes) {
                continue;
            }
            const auto solid_lava =
                visibility::ConvexPolyhedron::from_planes(planes, result, kBrushTolerance);
            if (result.ok()) {
                map.hazards.push_back({solid_lava.bounds(), "lava"});
            }
        }
        const bool solid = (contents & q3::kContentsSolid) != 0;
        const bool clip = (contents & q3::kContentsPlayerClip) != 0;
        if (!solid && !clip) {
            continue; // water, fog, triggers, hints: nothing to bump into
        }
        const bool translucent = (contents & q3::kContentsTranslucent) != 0;
        bool draws = false;
        bool see_through = false;
        planes.clear();
        for (const q3::BrushSide& side : bsp.sides_of(brush)) {
            const q3::Plane& plane = bsp.planes[static_cast<std::size_t>(side.plane)];
            planes.push_back({plane.normal, plane.dist});
            const q3::Shader& shader = bsp.shaders[static_cast<std::size_t>(side.shader)];
            const bool side_draws = (shader.surface_flags & q3::kSurfNoDraw) == 0;
            draws = draws || side_draws;
            see_through = see_through || (side_draws && lets_sight_through(shader.name, scripts));
        }
        if (solid && translucent) {
            ++map.stats.translucent_skipped;
        } else if (solid && !draws) {
            ++map.stats.nodraw_skipped;
        } else if (solid && see_through) {
            ++map.stats.see_through_skipped;
            // The compiler's vis stopped here as at a wall: the PVS is opened through it.
            if (planes.size() <= kMaxBrushPlanes) {
                visibility::PolyhedronResult result;
                const auto brush_solid =
                    visibility::ConvexPolyhedron::from_planes(planes, result, kBrushTolerance);
                if (result.ok()) {
                    map.see_through.push_back(brush_solid.bounds());
                }
            }
        }
        const bool opaque = solid && !translucent && draws && !see_through;
        std::uint32_t ours = 0;
        ours |= solid ? contents_solid : 0u;
        ours |= clip ? contents_player_clip : 0u;
        ours |= translucent ? contents_translucent : 0u;
        detail::add_brush(map, planes, ours, opaque);
    }

    // Curved surfaces of the world that the game draws opaque: not occluders, but they
    // block sight (curved_surface.hpp).
    for (const q3::Patch& patch : bsp.patches) {
        if (patch.surface < world.first_surface ||
            patch.surface >= world.first_surface + world.num_surfaces) {
            continue; // a door's or a platform's: moves, not part of the static world
        }
        const q3::Shader& shader = bsp.shaders[static_cast<std::size_t>(patch.shader)];
        if ((shader.surface_flags & q3::kSurfNoDraw) != 0 ||
            (shader.content_flags & q3::kContentsTranslucent) != 0 ||
            lets_sight_through(shader.name, scripts)) {
            continue;
        }
        const bool finite = std::all_of(patch.points.begin(), patch.points.end(), [](glm::vec3 p) {
            return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
        });
        if (finite) {
            map.opaque_patches.push_back({patch.width, patch.height, patch.points});
        }
    }
    map.stats.opaque_patches = map.opaque_patches.size();

    auto entities = parse_entities(bsp.entities, bsp.file);
    if (!entities) {
        return entities.error();
    }
    auto spawns = spawn_points_from(entities.value(), bsp.file);
    if (!spawns) {
        return spawns.error();
    }
    map.spawn_points = std::move(spawns).value();
    for (std::size_t i = 0; i < entities.value().size(); ++i) {
        const Entity& entity = entities.value()[i];
        if (entity.value("classname") != "trigger_hurt") {
            continue;
        }
        const std::string damage_text(entity.value("dmg"));
        // Quake 3's default damage is 5; strtol saturates on huge values.
        const long damage = damage_text.empty() ? 5 : std::strtol(damage_text.c_str(), nullptr, 10);
        if (damage < kLethalHurtDamage) {
            continue;
        }
        const std::string_view model = entity.value("model");
        const long index = model.size() > 1 && model[0] == '*'
                               ? std::strtol(std::string(model.substr(1)).c_str(), nullptr, 10)
                               : -1;
        if (index <= 0 || static_cast<std::size_t>(index) >= bsp.models.size()) {
            return LoadError{bsp.file, q3::lump_label(q3::Lump::entities),
                             "entity " + std::to_string(i) + " (trigger_hurt): model \"" +
                                 std::string(model) + "\" is not a brush model of this map (" +
                                 std::to_string(bsp.models.size()) + " models)"};
        }
        const q3::Model& volume = bsp.models[static_cast<std::size_t>(index)];
        visibility::Aabb box{volume.mins, volume.maxs};
        if (!std::isfinite(box.min.x + box.min.y + box.min.z + box.max.x + box.max.y + box.max.z) ||
            box.is_empty()) {
            continue; // nothing usable to avoid
        }
        map.hazards.push_back({box, "trigger_hurt dmg " + std::to_string(damage)});
    }
    detail::finish_map(map);
    map.pvs = std::make_shared<const Pvs>(bsp, map.see_through);
    return map;
}

Result<Map> load_q3_map_from_pk3(const std::filesystem::path& pk3, std::string_view name,
                                 const ShaderScripts* scripts) {
    const std::string entry = "maps/" + std::string(name) + ".bsp";
    auto bytes = read_pk3_entry(pk3, entry);
    if (!bytes) {
        return bytes.error();
    }
    auto bsp = q3::parse_q3_bsp(bytes.value(), pk3.string() + ":" + entry);
    if (!bsp) {
        return bsp.error();
    }
    return map_from_q3_bsp(bsp.value(), std::string(name), scripts);
}

Result<Map> load_q3_map_from_bsp(const std::filesystem::path& bsp_file,
                                 const ShaderScripts* scripts) {
    auto bsp = q3::read_q3_bsp_file(bsp_file);
    if (!bsp) {
        return bsp.error();
    }
    return map_from_q3_bsp(bsp.value(), bsp_file.stem().string(), scripts);
}

} // namespace dsoc::maps
