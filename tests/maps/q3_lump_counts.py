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
                       shader lets sight through
  see_through          world brushes with CONTENTS_SOLID, without CONTENTS_TRANSLUCENT,
                       with a side lacking SURF_NODRAW and a drawn side whose shader lets
                       sight through
  spawn_points         entities of the spawn classes (found with a regular expression)
  patches              surfaces of type 2 (curved patches)
  opaque_patches       of those, surfaces of model 0 whose shader lacks SURF_NODRAW and
                       CONTENTS_TRANSLUCENT and does not let sight through
  shader_scripts       scripts read, when every one was read whole and some define a
                       shader (else 0: the name hints decide)
  shader_definitions   distinct shader names the scripts define (case-insensitive)
Whether a shader lets sight through: without --scripts-dir, when its name sounds so
(grate, fence, window, ...). With --scripts-dir DIR, every "scripts/*.shader" entry
directly in scripts/ of every .pk3 directly in DIR is read with this file's own
tokenizer and parser, and the renderer's rule decides (see `shader_sight`); a name no
script defines is opaque when the scripts were read whole (some found, none malformed or
unreadable, some shader defined), and goes by its name otherwise.
Usage: q3_lump_counts.py [--scripts-dir DIR] PK3 MAP [MAP...]
Prints one JSON object per map, one a line.
"""
import json
import os
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
SCRIPT_LIMIT = 8 * 1024 * 1024  # longer scripts are not read (and leave the set not whole)
SPAWN_CLASSES = {"info_player_deathmatch", "info_player_start", "team_CTF_redspawn",
                 "team_CTF_bluespawn", "team_CTF_redplayer", "team_CTF_blueplayer"}


# One script token a match: white space, a // comment, a /* */ comment (to the end when
# unclosed) and a quoted string (likewise) are told apart by the group that matched;
# anything else runs to the next white space.
SCRIPT_TOKEN = re.compile(rb'(\s+)|(//[^\n]*)|(/\*.*?(?:\*/|\Z))|"([^"]*)"?|(\S+)', re.DOTALL)


def script_tokens(text):
    """(token, line) for each token of `text` (bytes), the line where it starts."""
    line = 1
    for match in SCRIPT_TOKEN.finditer(text):
        blank, comment, block, quoted, word = match.groups()
        if quoted is not None or word is not None:
            yield (word if word is not None else quoted), line
        line += match.group(0).count(b"\n")


# The keywords the rule reads, with how many arguments each takes (deformVertexes: its
# type; the rest of its line is numbers and wave names).
KEYWORD_ARGUMENTS = {b"surfaceparm": 1, b"skyparms": 3, b"deformvertexes": 1, b"portal": 0,
                     b"alphafunc": 1, b"blendfunc": 2}
ONE_WORD_BLENDS = ([b"add"], [b"filter"], [b"blend"])


def shader_sight(body, stages):
    """True when a shader lets sight through: `body` lists its statements of the keywords
    of KEYWORD_ARGUMENTS as (stage number or 0 outside stages, keyword, arguments), and it
    has `stages` stages. The renderer's rule: a sky (skyparms, surfaceparm sky) never does;
    otherwise it does when it has no stage, when its first stage is alpha-tested or blended
    (any blendFunc but GL_ONE GL_ZERO; add, filter and blend are blends), when its vertices
    move (deformVertexes but normal), when it is a portal, when it is nodraw."""
    general = [(keyword, args) for stage, keyword, args in body if stage == 0]
    parms = {args[0] for keyword, args in general if keyword == b"surfaceparm" and args}
    if b"sky" in parms or any(keyword == b"skyparms" for keyword, _ in general):
        return False
    if b"nodraw" in parms or any(keyword == b"portal" for keyword, _ in general):
        return True
    if any(keyword == b"deformvertexes" and args[:1] != [b"normal"] for keyword, args in general):
        return True
    if stages == 0:
        return True
    for stage, keyword, args in body:
        if stage != 1:
            continue
        if keyword == b"alphafunc":
            return True
        if keyword == b"blendfunc" and args[:2] != [b"gl_one", b"gl_zero"]:
            return True
    return False


def parse_script(text):
    """The shaders `text` defines, as [(lower-case name, lets sight through)], and whether
    it reads whole. Malformed text (a stray brace, a name with no body, a stage in a stage,
    a shader not closed, text over SCRIPT_LIMIT) ends the reading: the shaders closed
    before it are kept."""
    if len(text) > SCRIPT_LIMIT:
        return [], False
    tokens = list(script_tokens(text))
    shaders = []
    i = 0
    while i < len(tokens):
        name = tokens[i][0]
        if name in (b"{", b"}") or i + 1 >= len(tokens) or tokens[i + 1][0] != b"{":
            return shaders, False
        i += 2
        body, stage, stages = [], 0, 0
        while True:
            if i >= len(tokens):
                return shaders, False  # not closed
            token, line = tokens[i]
            i += 1
            if token == b"{":
                if stage:
                    return shaders, False  # a stage in a stage
                stages += 1
                stage = stages
            elif token == b"}":
                if not stage:
                    break
                stage = 0
            elif token.lower() in KEYWORD_ARGUMENTS:
                # Its arguments, as the game's parser takes them: from its own line, up to
                # a brace, as many as it reads (blendFunc one for its one-word forms).
                keyword, args = token.lower(), []
                while len(args) < KEYWORD_ARGUMENTS[keyword] and i < len(tokens) \
                        and tokens[i][1] == line and tokens[i][0] not in (b"{", b"}") \
                        and not (keyword == b"blendfunc" and args[:1] in ONE_WORD_BLENDS):
                    args.append(tokens[i][0].lower())
                    i += 1
                body.append((stage, keyword, args))
            # Any other word means nothing here and is stepped over alone (an argument of
            # a keyword the rule does not need included).
        shaders.append((name.lower(), shader_sight(body, stages)))
    return shaders, True


def read_scripts(directory):
    """Every script of every .pk3 in `directory`: ({lower-case name: lets sight through},
    scripts read, whether all read whole). A name defined more than once lets sight
    through when any of its definitions does."""
    sight, scripts, whole = {}, 0, True
    for pk3 in sorted(os.listdir(directory)):
        path = os.path.join(directory, pk3)
        if not pk3.lower().endswith(".pk3") or not os.path.isfile(path):
            continue
        try:
            archive = zipfile.ZipFile(path)
        except (OSError, zipfile.BadZipFile):
            whole = False
            continue
        with archive:
            for entry in archive.namelist():
                folder, _, file = entry.lower().partition("/")
                if folder != "scripts" or "/" in file or len(file) <= len(".shader") \
                        or not file.endswith(".shader"):
                    continue
                try:
                    text = archive.read(entry)
                except (OSError, zipfile.BadZipFile):
                    whole = False
                    continue
                scripts += 1
                shaders, read_whole = parse_script(text)
                whole = whole and read_whole
                for name, through in shaders:
                    sight[name] = sight.get(name, False) or through
    return sight, scripts, whole and scripts > 0


def lumps(data):
    magic, version = struct.unpack_from("<4si", data, 0)
    assert magic == b"IBSP" and version == 46, "not an IBSP v46 file"
    directory = struct.unpack_from("<34i", data, 8)
    return [data[directory[2 * i]:directory[2 * i] + directory[2 * i + 1]] for i in range(17)]


def lets_sight_through(name, scripts):
    """Whether shader `name` lets sight through, by `scripts` (read_scripts()) or None."""
    if scripts is not None:
        sight, _, whole = scripts
        if name.lower() in sight:
            return sight[name.lower()]
        if whole and sight:
            return False  # no script: the game draws its image, opaque
    return bool(SEE_THROUGH.search(name))


def count(data, scripts=None):
    lump = lumps(data)
    shaders = [(flags, contents, lets_sight_through(name.split(b"\0")[0], scripts))
               for name, flags, contents in struct.iter_unpack("<64sii", lump[1])]
    brushes = list(struct.iter_unpack("<3i", lump[8]))
    sides = list(struct.iter_unpack("<2i", lump[9]))
    models = list(struct.iter_unpack("<6f4i", lump[7]))
    first_brush, num_brushes = models[0][8], models[0][9]
    collision = opaque = see_through = 0
    for first_side, num_sides, shader in brushes[first_brush:first_brush + num_brushes]:
        contents = shaders[shader][1] & 0xFFFFFFFF
        if contents & (CONTENTS_SOLID | CONTENTS_PLAYERCLIP):
            collision += 1
        side_shaders = [shaders[s] for _, s in sides[first_side:first_side + num_sides]]
        drawn = [see for flags, _, see in side_shaders if not flags & SURF_NODRAW]
        if contents & CONTENTS_SOLID and not contents & CONTENTS_TRANSLUCENT and drawn:
            if any(drawn):
                see_through += 1
            else:
                opaque += 1
    text = lump[0].split(b"\0")[0].decode("latin-1")
    classnames = re.findall(r'"classname"\s+"([^"]*)"', text)
    spawns = sum(1 for c in classnames if c in SPAWN_CLASSES)
    # Surfaces are 104-byte records: the shader is the first int, the type the third.
    surfaces = [struct.unpack_from("<3i", lump[13], off) for off in range(0, len(lump[13]), 104)]
    patches = sum(1 for _, _, kind in surfaces if kind == 2)
    first_surface, num_surfaces = models[0][6], models[0][7]
    opaque_patches = sum(1 for shader, _, kind in surfaces[first_surface:first_surface + num_surfaces]
                         if kind == 2 and not shaders[shader][0] & SURF_NODRAW
                         and not shaders[shader][1] & CONTENTS_TRANSLUCENT and not shaders[shader][2])
    sight, scripts_read, whole = scripts if scripts is not None else ({}, 0, False)
    return {"brushes": len(brushes), "world_brushes": num_brushes,
            "collision_candidates": collision, "opaque_candidates": opaque,
            "see_through": see_through, "spawn_points": spawns, "patches": patches, "opaque_patches": opaque_patches,
            "shader_scripts": scripts_read if whole and sight else 0, "shader_definitions": len(sight)}


def main():
    args = sys.argv[1:]
    scripts = None
    if args[:1] == ["--scripts-dir"] and len(args) >= 2:
        scripts = read_scripts(args[1])
        args = args[2:]
    if len(args) < 2 or args[0].startswith("--"):
        sys.exit(__doc__)
    with zipfile.ZipFile(args[0]) as pk3:
        names = {n.lower(): n for n in pk3.namelist()}
        for name in args[1:]:
            data = pk3.read(names["maps/%s.bsp" % name.lower()])
            print(json.dumps(dict(count(data, scripts), map=name)))


if __name__ == "__main__":
    main()
