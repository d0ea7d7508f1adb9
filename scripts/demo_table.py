#!/usr/bin/env python3
"""The table at the end of scripts/demo: the interest policies side by side on one map.

Input, per policy, the two files of one real run (dsoc-server and dsoc-simclient on
loopback, same map, bots and clients): the server's --stats-json and the clients'
--report. Optionally dsoc-eval's --json of the same map and population, for the
columns only its ray-cast oracle can give (pop-in, exposure).

Output: a Markdown table on stdout, columns aligned, one row per policy in the order
given. Figures:
  KiB/s per client     server bytes_sent / snapshots_sent * tick_rate / 1024 (a
                       snapshot is one client-tick), then that as a share of the
                       broadcast row's, when there is one
  updates/s            server entity_updates_sent / snapshots_sent * tick_rate
  known                simclient entities_known_per_client.mean
  heard only           simclient entities_heard_per_client.mean (of the known ones,
                       those sent only because heard: coarse, without angles)
  tick ms              server tick_cost_us.mean / 1000 (wall time of a tick, workers in
                       parallel)
  us/client-tick       server tick_cost_us.mean * ticks / snapshots_sent
  pop-in, exposure     dsoc-eval: popin_present / popin_lookahead, exposure (the
                       server's dsoc policy is the eval's dsoc-table; others by name)
A figure that is missing prints as "-".

Usage: demo_table.py [--eval EVAL_JSON] POLICY=SERVER_JSON,SIMCLIENT_JSON ...
       demo_table.py --eval-names POLICY ...   (dsoc-eval's --policy list for them)
"""

import json
import sys

# The eval's name for each server policy where they differ (server defaults: the
# baked table alone, docs/baked-visibility.md).
EVAL_NAMES = {"dsoc": "dsoc-table"}

COLUMNS = [
    ("policy", "l"),
    ("KiB/s per client", "r"),
    ("x broadcast", "r"),
    ("updates/s per client", "r"),
    ("entities known", "r"),
    ("heard only", "r"),
    ("tick ms", "r"),
    ("us/client-tick", "r"),
    ("pop-in", "r"),
    ("exposure", "r"),
]

# Printed under the table: what each column is, for a reader who has not read this file.
NOTES = """\
KiB/s, updates/s: what the server sent each client per second (server --stats-json);
entities known: mean per client, as the clients decoded them (simclient --report), of
them heard only: sent because heard, not seen (a 64-unit blob without angles; the
oracle judges sight, so they are not in its pop-in or exposure);
tick ms: the server's tick (wall time, its workers in parallel), mean; us/client-tick:
all tick time over all client-ticks. pop-in (visible from the eye / from anywhere
reachable within the latency allowance, not sent) and exposure (sent entities that
no such eye sees: what a wallhack could draw): dsoc-eval's ray-cast oracle on the same
map, viewers and bots, in-process (docs/evaluation.md)."""


def server_figures(server):
    """Per-client rates and tick cost from a server's --stats-json (dict)."""
    snapshots = server.get("snapshots_sent") or 0
    rate = server.get("tick_rate") or 0
    cost = (server.get("tick_cost_us") or {}).get("mean")
    out = {"bytes_per_s": None, "updates_per_s": None, "tick_ms": None, "us_per_client_tick": None}
    if snapshots > 0 and rate > 0:
        out["bytes_per_s"] = server.get("bytes_sent", 0) / snapshots * rate
        out["updates_per_s"] = server.get("entity_updates_sent", 0) / snapshots * rate
    if cost is not None:
        out["tick_ms"] = cost / 1000.0
        if snapshots > 0:
            out["us_per_client_tick"] = cost * server.get("ticks", 0) / snapshots
    return out


def eval_name(policy):
    """dsoc-eval's name of the server policy `policy`."""
    return EVAL_NAMES.get(policy, policy)


def eval_figures(evaluation, policy):
    """(pop-in present, pop-in lookahead, exposure) of `policy` in a dsoc-eval --json,
    or None when the eval did not run it."""
    name = eval_name(policy)
    for p in (evaluation or {}).get("policies", []):
        if p.get("name") == name:
            return p.get("popin_present"), p.get("popin_lookahead"), p.get("exposure")
    return None


def rows(runs, evaluation=None):
    """runs: [(policy, server dict, simclient dict)]. Returns the table's cells, one
    list of strings per policy, in the order of COLUMNS."""
    figures = [(policy, server_figures(server), simclient) for policy, server, simclient in runs]
    broadcast = next((f["bytes_per_s"] for p, f, _ in figures if p == "broadcast"), None)
    out = []
    for policy, f, simclient in figures:
        known = (simclient.get("entities_known_per_client") or {}).get("mean")
        heard = (simclient.get("entities_heard_per_client") or {}).get("mean")
        share = None
        if broadcast and f["bytes_per_s"] is not None:
            share = f["bytes_per_s"] / broadcast
        judged = eval_figures(evaluation, policy)
        popin = exposure = None
        if judged is not None:
            present, lookahead, exposure = judged
            if present is not None and lookahead is not None:
                popin = "%d / %d" % (present, lookahead)
        out.append([
            policy,
            fmt(f["bytes_per_s"], 1, scale=1 / 1024),
            fmt(share, 2, suffix="x"),
            fmt(f["updates_per_s"], 0),
            fmt(known, 1),
            fmt(heard, 1),
            fmt(f["tick_ms"], 2),
            fmt(f["us_per_client_tick"], 1),
            popin or "-",
            fmt(exposure, 0, scale=100, suffix="%"),
        ])
    return out


def fmt(value, digits, scale=1.0, suffix=""):
    if value is None:
        return "-"
    return "{:,.{}f}{}".format(value * scale, digits, suffix)


def markdown(cells):
    """The header and `cells` as a Markdown table whose columns line up in a terminal."""
    table = [[name for name, _ in COLUMNS]] + cells
    widths = [max(len(row[i]) for row in table) for i in range(len(COLUMNS))]

    def line(row):
        padded = [
            row[i].ljust(widths[i]) if align == "l" else row[i].rjust(widths[i])
            for i, (_, align) in enumerate(COLUMNS)
        ]
        return "| " + " | ".join(padded) + " |"

    rule = "|" + "|".join(
        "-" * (widths[i] + 1) + ":" if align == "r" else "-" * (widths[i] + 2)
        for i, (_, align) in enumerate(COLUMNS)
    ) + "|"
    return "\n".join([line(table[0]), rule] + [line(r) for r in table[1:]])


def main(argv):
    evaluation = None
    runs = []
    args = list(argv)
    if args[:1] == ["--eval-names"]:
        print(",".join(eval_name(p) for p in args[1:]))
        return 0
    while args:
        arg = args.pop(0)
        if arg == "--eval":
            with open(args.pop(0)) as f:
                evaluation = json.load(f)
            continue
        policy, _, files = arg.partition("=")
        server_path, _, simclient_path = files.partition(",")
        if not policy or not server_path or not simclient_path:
            print("demo_table: expected POLICY=SERVER_JSON,SIMCLIENT_JSON, got " + arg,
                  file=sys.stderr)
            return 2
        with open(server_path) as f:
            server = json.load(f)
        with open(simclient_path) as f:
            simclient = json.load(f)
        runs.append((policy, server, simclient))
    if not runs:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    print(markdown(rows(runs, evaluation)))
    print()
    print(NOTES)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
