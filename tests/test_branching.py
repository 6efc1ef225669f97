"""Branch statistics over seeds in ``dla.summarise`` and the report (``dlasweep.stats.branches``)."""

import numpy as np
import pytest

import dlasweep as dla
from dlasweep.measures import tree
from dlasweep.reporting.folder import report
from dlasweep.stats import branches as branching
from dlasweep.stats.fit import ensemble
from test_report import ALWAYS, synthetic_sweep


@pytest.fixture(scope="module")
def sweep():
    return synthetic_sweep({"stickiness": [1.0, 0.5]}, counts=(300, 3000), seeds=4, parents=True)


def test_summarise_gives_the_ratio_over_seeds_with_its_interval(sweep):
    s = dla.summarise(sweep, resamples=20)
    for i, stickiness in enumerate([1.0, 0.5]):
        ratios, dims, counts = [], [], []
        for k in np.flatnonzero(sweep["cluster_stickiness"].values == stickiness):
            b = tree.branching(dla.cluster_parents(sweep, int(k)))
            ratios.append(b["bifurcation_ratio"])
            dims.append(b["chemical_dimension"])
            counts.append(b["branch_counts"])
        at = s.isel(stickiness=i, size=0)
        e = ensemble(ratios)
        assert float(at["bifurcation_ratio"]) == pytest.approx(e.mean)
        assert (float(at["bifurcation_ratio_ci_lo"]), float(at["bifurcation_ratio_ci_hi"])) == pytest.approx(
            (e.ci_lo, e.ci_hi))
        assert float(at["chemical_dimension"]) == pytest.approx(ensemble(dims).mean)
        np.testing.assert_allclose(at["bifurcation_ratio_cluster"].values, ratios)
        top = max(map(len, counts))
        mean = np.mean([np.pad(c, (0, top - len(c))) for c in counts], axis=0)
        np.testing.assert_allclose(at["branch_count"].values[:top], mean)
        assert int(at["branch_clusters"]) == 4
        # DLA of 3000 on the lattice: R_b between 3 and 6, d_l about D
        assert 3 < e.mean < 6 and 1.3 < float(at["chemical_dimension"]) < 2
    for name, var in s.items():
        assert var.attrs.get("long_name"), name


def test_too_few_clusters_give_no_interval():
    s = dla.summarise(synthetic_sweep({"stickiness": [1.0]}, counts=(300, 2000), seeds=2, parents=True),
                      resamples=20)
    assert np.isfinite(s["bifurcation_ratio"]).all() and np.isnan(s["bifurcation_ratio_ci_lo"]).all()


def test_files_without_parents_have_no_branching():
    s = dla.summarise(synthetic_sweep({"stickiness": [1.0]}, counts=(100, 300), seeds=2), resamples=20)
    assert "bifurcation_ratio" not in s


def test_the_report_draws_the_branching_and_a_row_per_configuration(sweep, tmp_path):
    names = {p.name for p in report(sweep, tmp_path)}
    assert names == ALWAYS | {"branching.png"}
    text = (tmp_path / "report.md").read_text()
    section = text[text.index("## Branching"):]
    s = dla.summarise(sweep)
    for stickiness in (1.0, 0.5):
        value = float(s["bifurcation_ratio"].sel(stickiness=stickiness, size=0))
        assert f"| stickiness={stickiness} | 4 |" in section and f"{value:.2f} [" in section
    assert "(branching.png)" in text


def test_the_ratio_line_falls_by_the_ratio_through_the_counts():
    line = branching.ratio_line([500.0, 100.0, 20.0, 3.0, 1.0], 5.0)
    np.testing.assert_allclose(line, [500, 100, 20, 4, 0.8])
