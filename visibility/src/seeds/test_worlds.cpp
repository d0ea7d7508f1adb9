#include "dsoc/visibility/seeds/test_worlds.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <random>
#include <vector>

namespace dsoc::visibility {
namespace {

using Rng = std::mt19937;

float uniform(Rng& rng, float lo, float hi) {
    return std::uniform_real_distribution<float>(lo, hi)(rng);
}

void add_box(OccluderWorld& world, glm::vec3 lo, glm::vec3 hi) {
    (void)world.add(ConvexPolyhedron::from_aabb(Aabb{lo, hi}));
}

/// A box cut by up to `cuts` random planes that keep its centre (a bevelled brush).
ConvexPolyhedron make_cut_box(Rng& rng, glm::vec3 c, glm::vec3 h, int cuts) {
    std::vector<Plane> planes = {{{1, 0, 0}, c.x + h.x}, {{-1, 0, 0}, -(c.x - h.x)},
                                 {{0, 1, 0}, c.y + h.y}, {{0, -1, 0}, -(c.y - h.y)},
                                 {{0, 0, 1}, c.z + h.z}, {{0, 0, -1}, -(c.z - h.z)}};
    for (int k = 0; k < cuts; ++k) {
        glm::vec3 n(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
        if (glm::length(n) < 0.2f) {
            continue;
        }
        n = glm::normalize(n);
        const glm::vec3 p = c + h * glm::vec3(uniform(rng, -0.6f, 0.6f), uniform(rng, -0.6f, 0.6f),
                                              uniform(rng, -0.6f, 0.6f));
        if (glm::dot(n, c - p) > 0.0f) {
            n = -n;
        }
        planes.push_back({n, glm::dot(n, p)});
    }
    PolyhedronResult result;
    return ConvexPolyhedron::from_planes(planes, result);
}

} // namespace

ConvexPolyhedron make_rotated_box(glm::vec3 center, glm::vec3 half_extents, float yaw) {
    const glm::vec3 ax(std::cos(yaw), std::sin(yaw), 0.0f);
    const glm::vec3 ay(-std::sin(yaw), std::cos(yaw), 0.0f);
    const glm::vec3 az(0.0f, 0.0f, 1.0f);
    const glm::vec3 axes[3] = {ax, ay, az};
    std::vector<Plane> planes;
    for (int i = 0; i < 3; ++i) {
        const float c = glm::dot(axes[i], center);
        planes.push_back({axes[i], c + half_extents[i]});
        planes.push_back({-axes[i], -(c - half_extents[i])});
    }
    PolyhedronResult result;
    return ConvexPolyhedron::from_planes(planes, result);
}

TestWorld make_corridor_world(std::uint32_t seed, int rooms_x, int rooms_y) {
    Rng rng(seed);
    TestWorld out;
    constexpr float kRoom = 512.0f;
    constexpr float kHeight = 256.0f;
    constexpr float kWall = 16.0f;
    constexpr float kDoor = 96.0f;
    constexpr float kDoorHeight = 128.0f;
    auto& world = out.world;
    // Floor slabs, one per room.
    for (int x = 0; x < rooms_x; ++x) {
        for (int y = 0; y < rooms_y; ++y) {
            const glm::vec3 lo(x * kRoom, y * kRoom, -16.0f);
            add_box(world, lo, lo + glm::vec3(kRoom, kRoom, 16.0f));
        }
    }
    // Walls along x (constant y) and along y (constant x), with a doorway in each
    // interior wall segment (at a random position) and solid outer walls.
    auto wall = [&](bool along_x, float fixed, float from, float to, bool door) {
        auto box = [&](float a0, float a1, float z0, float z1) {
            if (a1 - a0 < 1.0f) {
                return;
            }
            if (along_x) {
                add_box(world, {a0, fixed - kWall * 0.5f, z0}, {a1, fixed + kWall * 0.5f, z1});
            } else {
                add_box(world, {fixed - kWall * 0.5f, a0, z0}, {fixed + kWall * 0.5f, a1, z1});
            }
        };
        if (!door) {
            box(from, to, 0.0f, kHeight);
            return;
        }
        const float centre = uniform(rng, from + kDoor, to - kDoor);
        box(from, centre - kDoor * 0.5f, 0.0f, kHeight);
        box(centre + kDoor * 0.5f, to, 0.0f, kHeight);
        box(centre - kDoor * 0.5f, centre + kDoor * 0.5f, kDoorHeight, kHeight);
    };
    for (int y = 0; y <= rooms_y; ++y) {
        for (int x = 0; x < rooms_x; ++x) {
            const bool outer = y == 0 || y == rooms_y;
            wall(true, y * kRoom, x * kRoom, (x + 1) * kRoom, !outer);
        }
    }
    for (int x = 0; x <= rooms_x; ++x) {
        for (int y = 0; y < rooms_y; ++y) {
            const bool outer = x == 0 || x == rooms_x;
            wall(false, x * kRoom, y * kRoom, (y + 1) * kRoom, !outer);
        }
    }
    // Furniture: crates and (sometimes rotated) pillars.
    for (int x = 0; x < rooms_x; ++x) {
        for (int y = 0; y < rooms_y; ++y) {
            const glm::vec3 base(x * kRoom, y * kRoom, 0.0f);
            const int items = 1 + static_cast<int>(rng() % 3);
            for (int i = 0; i < items; ++i) {
                const glm::vec3 c = base + glm::vec3(uniform(rng, 96, kRoom - 96),
                                                     uniform(rng, 96, kRoom - 96), 0.0f);
                if (rng() % 2 == 0) {
                    const float s = uniform(rng, 16, 48);
                    add_box(world, c - glm::vec3(s, s, 0), c + glm::vec3(s, s, 2 * s));
                } else {
                    const glm::vec3 h(uniform(rng, 12, 32), uniform(rng, 12, 32), kHeight * 0.5f);
                    (void)world.add(make_rotated_box(c + glm::vec3(0, 0, kHeight * 0.5f), h,
                                                     uniform(rng, 0.0f, 3.14159f)));
                }
            }
        }
    }
    out.play_area = Aabb{{0.0f, 0.0f, 0.0f}, {rooms_x * kRoom, rooms_y * kRoom, kHeight}};
    return out;
}

TestWorld make_city_world(std::uint32_t seed, int blocks_x, int blocks_y) {
    Rng rng(seed);
    TestWorld out;
    constexpr float kBlock = 512.0f;
    constexpr float kStreet = 192.0f;
    for (int x = 0; x < blocks_x; ++x) {
        for (int y = 0; y < blocks_y; ++y) {
            const glm::vec3 lo(x * (kBlock + kStreet), y * (kBlock + kStreet), 0.0f);
            // 1..4 buildings per block.
            const int split = static_cast<int>(rng() % 3);
            const int nx = split == 1 ? 2 : 1;
            const int ny = split == 2 ? 2 : 1;
            for (int i = 0; i < nx; ++i) {
                for (int j = 0; j < ny; ++j) {
                    const float w = kBlock / static_cast<float>(nx);
                    const float d = kBlock / static_cast<float>(ny);
                    const float height = uniform(rng, 96.0f, 1024.0f);
                    const glm::vec3 blo = lo + glm::vec3(i * w + 8, j * d + 8, 0);
                    const glm::vec3 bhi = lo + glm::vec3((i + 1) * w - 8, (j + 1) * d - 8, height);
                    if (rng() % 4 == 0) {
                        const glm::vec3 c = (blo + bhi) * 0.5f;
                        (void)out.world.add(make_cut_box(rng, c, (bhi - blo) * 0.5f, 3));
                    } else {
                        add_box(out.world, blo, bhi);
                    }
                }
            }
        }
    }
    out.play_area = Aabb{{-kStreet * 0.5f, -kStreet * 0.5f, 0.0f},
                         {blocks_x * (kBlock + kStreet), blocks_y * (kBlock + kStreet), 256.0f}};
    return out;
}

TestWorld make_random_world(std::uint32_t seed, int count, float extent) {
    Rng rng(seed);
    TestWorld out;
    for (int i = 0; i < count; ++i) {
        const glm::vec3 c(uniform(rng, 0, extent), uniform(rng, 0, extent),
                          uniform(rng, 0, extent));
        const glm::vec3 h(uniform(rng, 4, 128), uniform(rng, 4, 128), uniform(rng, 4, 128));
        switch (rng() % 3) {
        case 0:
            add_box(out.world, c - h, c + h);
            break;
        case 1:
            (void)out.world.add(make_rotated_box(c, h, uniform(rng, 0.0f, 3.14159f)));
            break;
        default:
            (void)out.world.add(make_cut_box(rng, c, h, 1 + static_cast<int>(rng() % 8)));
            break;
        }
    }
    out.play_area = Aabb{glm::vec3(0.0f), glm::vec3(extent)};
    return out;
}

TestWorld make_walls_world(std::uint32_t seed, int count, float extent) {
    Rng rng(seed);
    TestWorld out;
    for (int i = 0; i < count; ++i) {
        const float height = uniform(rng, 64, 512);
        const glm::vec3 c(uniform(rng, 0, extent), uniform(rng, 0, extent), height * 0.5f);
        const glm::vec3 h(uniform(rng, 64, 512), uniform(rng, 4, 16), height * 0.5f);
        (void)out.world.add(make_rotated_box(c, h, uniform(rng, 0.0f, 3.14159f)));
    }
    out.play_area = Aabb{{0.0f, 0.0f, 0.0f}, {extent, extent, 384.0f}};
    return out;
}

} // namespace dsoc::visibility
