#!/usr/bin/env python3
"""scripts/demo_table.py: the figures of scripts/demo's comparison table come from the
right fields, per client and per second, and print as an aligned Markdown table."""

import contextlib
import io
import json
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.environ.get(
    "DSOC_SCRIPTS_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "scripts")))
import demo_table  # noqa: E402


def server(bytes_sent, snapshots, updates, ticks=300, mean_us=1500.0, rate=30):
    return {"bytes_sent": bytes_sent, "snapshots_sent": snapshots,
            "entity_updates_sent": updates, "ticks": ticks, "tick_rate": rate,
            "tick_cost_us": {"mean": mean_us, "p99": 2 * mean_us}}


def simclient(known, heard=None):
    out = {"entities_known_per_client": {"mean": known, "p95": 2 * known}}
    if heard is not None:
        out["entities_heard_per_client"] = {"mean": heard, "p95": 2 * heard}
    return out


class DemoTable(unittest.TestCase):
    def test_server_figures_are_per_client_tick_times_the_tick_rate(self):
        # 9,600 snapshots = 32 clients x 300 ticks; 30 Hz.
        f = demo_table.server_figures(server(9_600 * 1024, 9_600, 9_600 * 50))
        self.assertAlmostEqual(f["bytes_per_s"], 1024 * 30)
        self.assertAlmostEqual(f["updates_per_s"], 50 * 30)
        self.assertAlmostEqual(f["tick_ms"], 1.5)
        self.assertAlmostEqual(f["us_per_client_tick"], 1500.0 * 300 / 9_600)

    def test_a_server_that_sent_no_snapshot_has_no_rates(self):
        f = demo_table.server_figures(server(0, 0, 0))
        self.assertIsNone(f["bytes_per_s"])
        self.assertIsNone(f["us_per_client_tick"])
        self.assertAlmostEqual(f["tick_ms"], 1.5)

    def test_rows_share_of_broadcast_and_the_oracle_columns(self):
        evaluation = {"policies": [
            {"name": "dsoc-table", "popin_present": 0, "popin_lookahead": 0, "exposure": 0.3},
            {"name": "pvs", "popin_present": 1, "popin_lookahead": 62, "exposure": 0.5}]}
        cells = demo_table.rows([
            ("dsoc", server(9_600 * 512, 9_600, 9_600), simclient(80.0, 30.5)),
            ("pvs", server(9_600 * 600, 9_600, 9_600), simclient(90.0)),
            ("broadcast", server(9_600 * 2048, 9_600, 9_600), simclient(231.0)),
        ], evaluation)
        names = [c[0] for c in demo_table.COLUMNS]
        dsoc, pvs, broadcast = (dict(zip(names, row)) for row in cells)
        self.assertEqual(dsoc["KiB/s per client"], "15.0")  # 512 B x 30 Hz / 1024
        self.assertEqual(dsoc["x broadcast"], "0.25x")
        self.assertEqual(broadcast["x broadcast"], "1.00x")
        self.assertEqual(dsoc["entities known"], "80.0")
        self.assertEqual(dsoc["heard only"], "30.5")
        self.assertEqual(pvs["heard only"], "-")  # a simclient report without the figure
        self.assertEqual(dsoc["pop-in"], "0 / 0")  # dsoc is the eval's dsoc-table
        self.assertEqual(dsoc["exposure"], "30%")
        self.assertEqual(pvs["pop-in"], "1 / 62")
        self.assertEqual(broadcast["pop-in"], "-")  # the eval did not run it
        self.assertEqual(broadcast["exposure"], "-")

    def test_without_a_broadcast_row_there_is_no_share(self):
        cells = demo_table.rows([("dsoc", server(100, 10, 10), simclient(5.0))])
        self.assertEqual(cells[0][2], "-")

    def test_markdown_columns_line_up(self):
        cells = demo_table.rows([
            ("dsoc", server(9_600 * 512, 9_600, 9_600), simclient(80.0)),
            ("broadcast", server(9_600 * 20480, 9_600, 9_600), simclient(231.0))])
        lines = demo_table.markdown(cells).splitlines()
        self.assertEqual(len(lines), 4)
        self.assertEqual(len({len(line) for line in lines}), 1, lines)
        self.assertTrue(lines[0].startswith("| policy"))
        self.assertRegex(lines[1], r"^\|-+\|(-+:\|)+$")
        self.assertIn("600.0", lines[3])  # 20,480 B a snapshot x 30 Hz = 600 KiB/s
        self.assertIn("1.00x", lines[3])

    def test_command_line_reads_the_files_and_maps_eval_names(self):
        with tempfile.TemporaryDirectory() as tmp:
            paths = {}
            for name, data in (("s.json", server(3_000, 30, 300)), ("c.json", simclient(7.0))):
                paths[name] = os.path.join(tmp, name)
                with open(paths[name], "w") as f:
                    json.dump(data, f)
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                status = demo_table.main(["pvs=%s,%s" % (paths["s.json"], paths["c.json"])])
            self.assertEqual(status, 0)
            self.assertIn("| pvs ", out.getvalue())
            self.assertIn("entities known: mean per client", out.getvalue())
            with contextlib.redirect_stdout(io.StringIO()) as names:
                demo_table.main(["--eval-names", "dsoc", "pvs"])
            self.assertEqual(names.getvalue().strip(), "dsoc-table,pvs")
            with contextlib.redirect_stderr(io.StringIO()):
                self.assertEqual(demo_table.main(["pvs=only-one-file.json"]), 2)


if __name__ == "__main__":
    unittest.main()
