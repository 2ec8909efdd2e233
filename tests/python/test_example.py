"""examples/sweep_error_vs_time.py runs as a user runs it and its figure and table say what a
work-precision sweep must: a finer step costs more run time and errs less."""
import csv
import os
import subprocess
import sys

import numpy as np
from PIL import Image

from conftest import SOURCE, scene


def test_the_sweep_example_plots_error_against_run_time(tmp_path):
    figure, table = tmp_path / "sweep.png", tmp_path / "sweep.csv"
    subprocess.run([sys.executable, os.path.join(SOURCE, "examples", "sweep_error_vs_time.py"),
                    "--scene", scene("single_sphere"), "--values", "0.05", "0.1", "--substeps", "1", "4",
                    "--reference", "16", "--duration", "2", "--output", str(figure), "--csv", str(table)],
                   check=True, capture_output=True, text=True)
    image = np.asarray(Image.open(figure).convert("RGB"))
    assert image.shape == (528, 768, 3)
    assert (image < 128).any() and (image > 200).any()  # axes, curves and a white page
    with open(table) as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4 and all(r["status"] == "ok" for r in rows)
    for value in ("0.05", "0.1"):
        coarse, fine = [r for r in rows if float(r["value"]) == float(value)]
        assert int(coarse["substeps"]) == 1 and int(fine["substeps"]) == 4
        assert float(fine["error"]) < float(coarse["error"]) / 2, value
        assert float(fine["wall"]) > float(coarse["wall"]), value
        assert float(fine["dt"]) == float(coarse["dt"]) / 4
