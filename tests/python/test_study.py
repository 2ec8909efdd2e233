"""springy.study: the work-precision runs' data as numpy arrays."""
import os

import numpy as np

import springy
from conftest import SOURCE


def test_a_quick_accuracy_study_gives_its_points_and_orders_as_arrays(tmp_path):
    tables = springy.study("accuracy", tmp_path / "study", quick=True, repeats=1)
    assert (tmp_path / "study" / "accuracy.md").exists()
    points, orders = tables["accuracy"], tables["accuracy-orders"]
    assert set(points) == {"case", "integrator", "dt", "error", "wall_per_sim_second", "stable"}
    for column in ("dt", "error", "wall_per_sim_second"):
        assert points[column].dtype == np.float64 and np.all(points[column] > 0), column
    assert points["integrator"].dtype.kind == "U" and len(points["case"]) == len(points["dt"])
    # The measured orders are the methods' own (the C++ suite checks them within 0.2; the
    # arrays carry them unchanged).
    for integrator, theory in (("explicit_euler", 1), ("verlet", 2), ("rk4", 4)):
        rows = (orders["integrator"] == integrator) & (orders["case"] == "strut")
        assert rows.sum() == 1
        assert orders["theory"][rows][0] == theory
        assert abs(orders["order"][rows][0] - theory) < 0.2, integrator
    # Error falls with the step for each method on each case.
    for case in np.unique(points["case"]):
        for integrator in ("verlet", "rk4"):
            rows = (points["case"] == case) & (points["integrator"] == integrator) & (points["stable"] == 1)
            dt, error = points["dt"][rows], points["error"][rows]
            order = np.argsort(dt)
            assert np.all(np.diff(error[order]) > 0), (case, integrator)


def test_the_documented_studies_read_back():
    tables = springy.load_study(os.path.join(SOURCE, "docs"))
    assert {"accuracy", "accuracy-orders", "accuracy-contact", "stability"} <= set(tables)
    contact = tables["accuracy-contact"]
    assert len(contact["scene"]) == len(contact["wall_per_sim_second"]) > 10
