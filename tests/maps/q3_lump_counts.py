#!/usr/bin/env python3
"""Independent reading of Quake 3 BSP maps for the dsoc loader tests.

Reads maps/<name>.bsp out of a .pk3 with zipfile and counts, with struct.iter_unpack
over whole lumps (not the C++ loader's per-record reader), what dsoc-mapinfo reports
before any geometry is computed:
  brushes              records in the brushes lump
  world_brushes        brushes of model 0
  collision_candidates world brushes whose shader has CONTENTS_SOLID or CONTENTS_PLAYERCLIP
  opaque_candidates    world brushes with CONTENTS_SOLID, without CONTENTS_TRANSLUCENT,
                       with at least one side lacking SURF_NODRAW, and no drawn side whose
                       shader name looks see-through (grate, fence, window, ...)
  spawn_points         entities of the spawn classes (found with a regular expression)
  patches              surfaces of type 2 (curved patches)
Usage: q3_lump_counts.py PK3 MAP [MAP...]   prints one JSON object per map, one a line.
"""
import json
import re
import struct
import sys
import zipfile

CONTENTS_SOLID = 0x1
CONTENTS_PLAYERCLIP = 0x10000
CONTENTS_TRANSLUCENT = 0x20000000
SURF_NODRAW = 0x80
SEE_THROUGH = re.compile(rb"grate|window|glass|fence|mesh|chain|cage|web|trans|alpha|net|grill|lattice",
                         re.IGNORECASE)
SPAWN_CLASSES = {"info_player_deathmatch", "info_player_start", "team_CTF_redspawn",
                 "team_CTF_bluespawn", "team_CTF_redplayer", "team_CTF_blueplayer"}


def lumps(data):
    magic, version = struct.unpack_from("<4si", data, 0)
    assert magic == b"IBSP" and version == 46, "not an IBSP v46 file"
    directory = struct.unpack_from("<34i", data, 8)
    return [data[directory[2 * i]:directory[2 * i] + directory[2 * i + 1]] for i in range(17)]


def count(data):
    lump = lumps(data)
    shaders = [(flags, contents, bool(SEE_THROUGH.search(name.split(b"\0")[0])))
               for name, flags, contents in struct.iter_unpack("<64sii", lump[1])]
    brushes = list(struct.iter_unpack("<3i", lump[8]))
    sides = list(struct.iter_unpack("<2i", lump[9]))
    models = list(struct.iter_unpack("<6f4i", lump[7]))
    first_brush, num_brushes = models[0][8], models[0][9]
    collision = opaque = 0
    for first_side, num_sides, shader in brushes[first_brush:first_brush + num_brushes]:
        contents = shaders[shader][1] & 0xFFFFFFFF
        if contents & (CONTENTS_SOLID | CONTENTS_PLAYERCLIP):
            collision += 1
        side_shaders = [shaders[s] for _, s in sides[first_side:first_side + num_sides]]
        drawn = [see for flags, _, see in side_shaders if not flags & SURF_NODRAW]
        if contents & CONTENTS_SOLID and not contents & CONTENTS_TRANSLUCENT and drawn and not any(drawn):
            opaque += 1
    text = lump[0].split(b"\0")[0].decode("latin-1")
    classnames = re.findall(r'"classname"\s+"([^"]*)"', text)
    spawns = sum(1 for c in classnames if c in SPAWN_CLASSES)
    # Surfaces are 104-byte records; the type is the third int.
    surface_types = [struct.unpack_from("<i", lump[13], off + 8)[0]
                     for off in range(0, len(lump[13]), 104)]
    patches = surface_types.count(2)
    return {"brushes": len(brushes), "world_brushes": num_brushes,
            "collision_candidates": collision, "opaque_candidates": opaque,
            "spawn_points": spawns, "patches": patches}


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    with zipfile.ZipFile(sys.argv[1]) as pk3:
        names = {n.lower(): n for n in pk3.namelist()}
        for name in sys.argv[2:]:
            data = pk3.read(names["maps/%s.bsp" % name.lower()])
            print(json.dumps(dict(count(data), map=name)))


if __name__ == "__main__":
    main()
