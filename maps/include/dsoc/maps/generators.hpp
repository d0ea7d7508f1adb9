#pragma once
// Procedural test worlds for scale tests. Deterministic: the same parameters (and
// seed) give the same MapSpec on every platform. Both worlds are closed (a floor
// under everything, walls around), so a walker cannot fall out. Floors are at z = 0;
// spawn points are 25 units above the floor (a Quake 3 player origin stands 24 above).

#include "dsoc/maps/map_spec.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace dsoc::maps {

/// A grid of city blocks (one building each, random height) separated by streets,
/// with low kerbs (step-up height) scattered on the streets, and an outer wall.
struct CityParams {
    int blocks_x = 8;            ///< [Limit: 1..256]
    int blocks_y = 8;            ///< [Limit: 1..256]
    float block_size = 512.0f;   ///< building footprint side [Units: world units] [Limit: >= 32]
    float street_width = 256.0f; ///< [Units: world units] [Limit: >= 64]
    float min_height = 128.0f;   ///< building height range [Units: world units] [Limit: > 0]
    float max_height = 1024.0f;  ///< [Limit: >= min_height]
    float glass_fraction = 0.1f; ///< share of buildings made of glass [Limit: 0..1]
    std::uint64_t seed = 1;
};

/// A grid of rooms joined by corridors (a random spanning tree plus a few loops),
/// under one ceiling, with crates and steps in the rooms.
struct RoomsParams {
    int rooms_x = 6;                  ///< [Limit: 1..128]
    int rooms_y = 6;                  ///< [Limit: 1..128]
    float room_size = 384.0f;         ///< interior side [Units: world units] [Limit: >= 160]
    float corridor_length = 256.0f;   ///< gap between rooms [Units: world units] [Limit: >= 32]
    float corridor_width = 96.0f;     ///< [Units: world units] [Limit: 48..room_size - 32]
    float height = 192.0f;            ///< floor to ceiling [Units: world units] [Limit: >= 96]
    float wall_thickness = 16.0f;     ///< [Units: world units] [Limit: >= 1]
    float extra_door_fraction = 0.2f; ///< share of non-tree neighbours also joined [Limit: 0..1]
    std::uint64_t seed = 1;
};

/// Every problem with the parameters, in words; empty when they are usable.
std::vector<std::string> validate(const CityParams& params);
std::vector<std::string> validate(const RoomsParams& params);

/// Precondition: validate(params) is empty.
[[nodiscard]] MapSpec generate_city(const CityParams& params);
[[nodiscard]] MapSpec generate_rooms(const RoomsParams& params);

} // namespace dsoc::maps
