"""`campaign report`: every table and figure, LaTeX that parses as a table fragment, the HTML page,
"no fit" instead of a crash, the lab comparison — on a synthetic index and on real quick-campaign
output when it is there."""

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from interphase.campaign.schema import load_campaign
from interphase.cli import main
from interphase.errors import InputError
from interphase.report.build import analyse, report_from_summaries
from interphase.report.synthetic import synthetic_summaries

ROOT = Path(__file__).resolve().parents[1]
LAB = ROOT / "tests" / "data" / "lab_example.csv"
FIGS = ("fig6_3", "fig6_5", "fig6_6", "fig6_7", "fig6_8", "fig6_9", "fig6_10a")


def check_latex(text: str) -> None:
    """A tabular fragment: balanced begin/end, booktabs rules in order, equal column count per row."""
    assert text.count(r"\begin{tabular}") == 1 == text.count(r"\end{tabular}")
    m = re.search(r"\\begin\{tabular\}\{([lrc]+)\}", text)
    assert m, "no column spec"
    ncol = len(m.group(1))
    body = text[m.end():text.index(r"\end{tabular}")]
    assert body.index(r"\toprule") < body.index(r"\midrule") < body.index(r"\bottomrule")
    rows = [r for r in body.split("\\\\") if r.strip() and "rule" not in r.split("\n")[-1] or "&" in r]
    for r in body.split("\\\\"):
        line = r.replace(r"\toprule", "").replace(r"\midrule", "").replace(r"\bottomrule", "").strip()
        if not line:
            continue
        if line.startswith(r"\multicolumn"):
            assert line.startswith(r"\multicolumn{%d}" % ncol)
            continue
        assert len(re.findall(r"(?<!\\)&", line)) == ncol - 1, line
    assert rows
    # braces balance (escaped ones excluded)
    plain = re.sub(r"\\[{}]", "", text)
    assert plain.count("{") == plain.count("}")
    assert "interphase-dem" in text          # provenance note


def check_outputs(folder: Path, groups, lab: bool = False) -> None:
    """Every figure drawn (PNG and PDF) or named among the figures not drawn, every table in its
    three forms, every link of the page to a file or an anchor that exists."""
    html = (folder / "index.html").read_text()
    not_drawn = html[html.index('id="not-drawn"'):] if 'id="not-drawn"' in html else ""
    for stem in FIGS + (("fig6_10b_lab",) if lab else ()):
        if not (folder / "figures" / f"{stem}.png").exists():
            assert f"Fig. {stem[3:].replace('_', '.')}:" in not_drawn, stem
            continue
        for ext in ("png", "pdf"):
            p = folder / "figures" / f"{stem}.{ext}"
            assert p.is_file() and p.stat().st_size > 1000, p
    tables = ["table_6_1_inputs", "correlations"] + [f"results_{g}" for g in groups] + (["lab_comparison"] if lab else [])
    for t in tables:
        for ext in ("csv", "md", "tex"):
            p = folder / "tables" / f"{t}.{ext}"
            assert p.is_file() and p.stat().st_size > 0, p
        check_latex((folder / "tables" / f"{t}.tex").read_text())
    links = re.findall(r'(?:href|src)="([^"]+)"', html)
    files = [link for link in links if not link.startswith("#")]
    assert files and all((folder / link).is_file() for link in files)
    ids = set(re.findall(r'id="([^"]+)"', html))
    anchors = [link[1:] for link in links if link.startswith("#")]
    assert anchors and all(a in ids for a in anchors)          # the contents list points at the page's parts
    for stem in FIGS:
        assert f"figures/{stem}.png" in html or f"Fig. {stem[3:].replace('_', '.')}:" in not_drawn


@pytest.fixture(scope="module")
def synthetic_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("rep")
    summ = synthetic_summaries(150, seed=11)
    res = report_from_summaries(summ, out, campaign=load_campaign(ROOT / "campaigns" / "group4.toml"), lab=LAB,
                                n_boot=30)
    return out, res, summ


def test_synthetic_report_writes_everything(synthetic_report):
    out, res, summ = synthetic_report
    groups = sorted(summ.loc[summ.test == "interface", "group"].unique())
    check_outputs(out, groups, lab=True)
    assert (out / "tables" / "table_6_2_random.tex").is_file()      # group4: Table 6.2 style
    assert all(p.is_file() for p in res.files)


def test_input_table_is_generated_from_the_campaign(synthetic_report):
    out = synthetic_report[0]
    t62 = pd.read_csv(out / "tables" / "table_6_2_random.csv")
    assert list(t62.columns) == ["variable", "A", "B", "C", "D", "E", "F", "G"]   # Table 6.2
    au = t62.set_index("variable").loc["Au/D50 [-]"]
    assert list(au) == [1, 2, 2, 4, 2, 4, 4]


def test_coefficients_table_has_fits_and_intervals(synthetic_report):
    out = synthetic_report[0]
    co = pd.read_csv(out / "tables" / "correlations.csv")
    e = co[(co.figure == "6.10a") & (co["slice"] == "all")].iloc[0]
    assert 27 <= e["c"] <= 33 and e["n"] == 150
    assert e["c 95% (profile)"].startswith("[")


def test_lab_comparison_table(synthetic_report):
    out = synthetic_report[0]
    lab = pd.read_csv(out / "tables" / "lab_comparison.csv")
    assert len(lab) == 6
    assert lab["δ predicted [°]"].notna().all() and lab["δ measured [°]"].notna().all()
    assert (lab["tan φμ [-]"].iloc[:4] == 0.1).all() and (lab["tan φμ [-]"].iloc[4:] == 0.2).all()
    assert (lab["φ from"] == "the campaign's simulated soil").all()
    err = lab["δ predicted [°]"] - lab["δ measured [°]"]
    assert np.allclose(lab["error [°]"], err)


def test_too_few_points_draw_and_say_no_fit(tmp_path):
    res = report_from_summaries(synthetic_summaries(4, seed=1), tmp_path, n_boot=0)
    co = pd.read_csv(tmp_path / "tables" / "correlations.csv")
    assert co["note"].str.contains("no fit: n = .* < 7", regex=True).all()
    assert (tmp_path / "figures" / "fig6_8.png").stat().st_size > 1000
    check_latex((tmp_path / "tables" / "correlations.tex").read_text())
    assert not res.warnings or all(isinstance(w, str) for w in res.warnings)


def test_the_analysis_is_a_model_of_tables_and_writes_nothing(tmp_path, monkeypatch):
    """analyse: the report's content from a summaries table alone (no store, no folder); every
    table the page shows is in the model, and nothing is written."""
    monkeypatch.chdir(tmp_path)
    summ = synthetic_summaries(150, seed=11)
    m = analyse(summ, n_boot=0)
    assert list(tmp_path.iterdir()) == []
    names = [t.name for t in m.tables]
    assert "correlations" in names and [n for n in names if n.startswith("results_")]
    assert len(m.points) == summ["test"].eq("interface").sum() and m.ensembles is None   # one seed a case
    assert m.chain.theta_r and m.criterion_check is not None and m.n_box == 2
    assert m.fits and all(f.spec is not None for f in m.fits)


def test_empty_index_still_writes_a_report(tmp_path):
    summ = synthetic_summaries(3, seed=1).iloc[0:0]
    res = report_from_summaries(summ, tmp_path, n_boot=0)
    assert (tmp_path / "index.html").is_file()
    assert any("no finished interface case" in w for w in res.warnings)


def test_bad_lab_file_names_the_column(tmp_path):
    """The report reads the lab/ format (interphase.lab): a bad file fails before anything is written,
    naming the file and the column."""
    bad = tmp_path / "lab.csv"
    bad.write_text(LAB.read_text().replace("tan_delta_peak", "tan_delta_at_peak"))
    out = tmp_path / "r"
    with pytest.raises(InputError, match="delta_peak") as exc:
        report_from_summaries(synthetic_summaries(3, seed=1), out, lab=bad, n_boot=0)
    assert str(bad) in str(exc.value) and not out.exists()


def test_cli_report_without_results_exit_2(tmp_path, capsys):
    toml = tmp_path / "c.toml"
    text = (ROOT / "campaigns" / "quick.toml").read_text().replace('name = "quick"', 'name = "nothing_here"')
    toml.write_text(text + '\n')
    code = main(["report", str(toml), "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert code == 2 and "campaign run" in err and "Traceback" not in err


@pytest.fixture(scope="module")
def quick_report(quick_campaign, tmp_path_factory):
    """`campaign report` of the real quick campaign (LIGGGHTS, 6 tiny cases; conftest.quick_campaign)
    with the laboratory table: built once (~11 s of CPU) for the two tests below that read it."""
    out = tmp_path_factory.mktemp("quick-report") / "report"
    code = main(["report", str(quick_campaign), "--out", str(out), "--lab", str(LAB), "--bootstrap", "20"])
    assert code == 0
    return out


@pytest.mark.liggghts
def test_real_quick_campaign_report(quick_report):
    """The quick campaign run for real (LIGGGHTS, 6 tiny cases; conftest.quick_campaign), reported."""
    tmp_path = quick_report
    check_outputs(tmp_path, ["quick"], lab=True)
    assert list((tmp_path / "figures").glob("curves_*.png"))
    assert list((tmp_path / "figures").glob("network_*.png"))
    co = pd.read_csv(tmp_path / "tables" / "correlations.csv")
    assert co["note"].str.startswith("no fit").all()       # 4 interface cases: nothing to fit, said so
    # the seed ensembles: one row per surface, two seeds each side: values, no interval, and the note says so
    ens = pd.read_csv(tmp_path / "tables" / "ensembles.csv")
    assert len(ens) == 2 and (ens["seeds"] == 2).all() and (ens["box_seeds"] == 2).all()
    assert (ens["tan_delta"] > 0).all() and ens["E"].notna().all()
    assert ens[["E_lo", "E_hi", "tan_delta_lo", "tan_delta_hi", "theta_r_lo"]].isna().all().all()
    assert ens["note"].str.contains("fewer than 3 seeds").all()


@pytest.mark.liggghts
def test_report_writes_every_run_as_one_small_summaries_file(quick_report):
    s = pd.read_csv(quick_report / "tables" / "summaries.csv")
    assert len(s) == 6 and list(s.columns[:5]) == ["case_id", "label", "physical_id", "group", "test"]
    # a physical case's seeds share its id, and only they do
    name = s["label"].str.replace(r"-s\d+$", "", regex=True)
    assert s["physical_id"].notna().all() and s.groupby(["group", name])["physical_id"].nunique().eq(1).all()
    assert s.groupby("physical_id")["seed"].nunique().eq(s.groupby("physical_id").size()).all()
    assert {"peak_stress_ratio", "theta_a_deg_92", "theta_r_surface_deg", "seed", "gradation", "friction_ps"} <= set(s.columns)
    box = s[s["test"].eq("box")].set_index("case_id")["peak_stress_ratio"]
    iface = s[s["test"].eq("interface")]
    assert np.allclose(iface["efficiency_run"], iface["peak_stress_ratio"].to_numpy() / box.loc[iface["pair_id"]].to_numpy(),
                       rtol=1e-5)
    assert s.loc[s["test"].eq("box"), "efficiency_run"].isna().all()
    assert "efficiency" not in s    # one name per E: the ensembles' E is elsewhere


def test_one_group_of_surfaces_holds_out_each_surface():
    """The committed quasi-2D Karlsruhe campaign (Group 1's 8 saw-teeth and, beside them, a flat and
    two measured lines, × 3 frictions; the measured group too small to fit without Group 1) is
    checked with each surface held out: every interior surface predicted at every friction from fits
    made without it; the lowest θa (0: the flat and the line that is non-dilative at its mesh step)
    and the highest lie outside the others' fits and keep that reason; held out, the chain misses the
    same cases by no less than in sample."""
    from interphase.campaign.results import CommittedCurves

    folder = ROOT / "studies" / "kfs_group1_2d" / "results"
    summ = pd.read_csv(folder / "summaries.csv", dtype={"case_id": str, "pair_id": str})
    checks = analyse(summ, campaign=None, store=CommittedCurves(folder / "curves.parquet"), n_boot=0).criterion_check
    assert set(checks["fold"]) == {"in-sample", "surface held out"}
    held = checks[checks["fold"] == "surface held out"]
    theta = held["theta_a_deg_92"].round(1)
    ends = theta.isin([theta.min(), theta.max()])
    assert len(held) == (checks["fold"] == "in-sample").sum() >= 24 and theta.min() == 0.0
    assert held.loc[ends, "error_deg"].isna().all() and held.loc[~ends, "error_deg"].notna().all()
    out = held[ends]
    assert out["note"].str.contains("outside the fitted range").all()
    got = held.dropna(subset=["error_deg"]).set_index("physical_case")["error_deg"]
    ins = checks[checks["fold"] == "in-sample"].set_index("physical_case")["error_deg"].loc[got.index]
    assert np.sqrt((got ** 2).mean()) >= np.sqrt((ins ** 2).mean())


def test_a_group_too_small_to_fit_without_the_rest_keeps_the_surface_fold():
    """Group 1 with a few surfaces of another group beside it (here its lowest tooth relabelled): the
    cases left without Group 1 cannot fit θa–θr per friction (3 a friction), so the check holds out
    each surface, not each group; relabelling changes no fit, so every held-out error is the one-group
    campaign's."""
    from interphase.campaign.results import CommittedCurves

    folder = ROOT / "studies" / "kfs_group1_2d" / "results"
    summ = pd.read_csv(folder / "summaries.csv", dtype={"case_id": str, "pair_id": str})
    store = CommittedCurves(folder / "curves.parquet")
    one = analyse(summ, campaign=None, store=store, n_boot=0).criterion_check
    low = summ["test"].eq("interface") & summ["label"].str.contains("-rt0.1-")
    assert low.sum() >= 9
    two = analyse(summ.assign(group=summ["group"].where(~low, "measured")), campaign=None, store=store,
                  n_boot=0).criterion_check
    assert set(two["fold"]) == {"in-sample", "surface held out"}
    key = ["fold", "physical_case"]
    a, b = one.set_index(key)["error_deg"].sort_index(), two.set_index(key)["error_deg"].sort_index()
    assert a.index.equals(b.index) and np.allclose(a, b, equal_nan=True)


def test_the_criterion_is_checked_against_every_case_in_sample_and_group_held_out(synthetic_report):
    """Synthetic cases follow a known chain (θr(θa, μ) and E(θr) with small noise): predicted δ must
    sit within a couple of degrees of the measured one in sample and with each group's points left
    out of the fits; the table says the error distribution and the largest miss; criterion.json is
    written and reads back as the same chain."""
    from interphase.analysis.criterion import check_summary, predict
    from interphase.criterion_fits import load_criterion

    out, res, summ = synthetic_report
    checks = res.criterion_check
    assert set(checks["fold"]) == {"in-sample", "group held out"}
    n_cases = len(res.points)
    for fold, g in checks.groupby("fold"):
        assert len(g) == n_cases                              # every case, once per fold
        s = check_summary(g)
        assert s["n"] >= 0.5 * n_cases and abs(s["mean"]) < 1.0 and s["max_abs"] < 6.0, (fold, s)
    assert check_summary(checks[checks["fold"] == "in-sample"])["n"] >= 0.8 * n_cases
    # Group 2 alone has flat-spaced surfaces: without it there is no Fig. 6.9 fit, and the rows say so
    g2 = checks[(checks["fold"] == "group held out") & (checks["group"] == "group2") & checks["flat_spaced"]]
    assert len(g2) and g2["error_deg"].isna().all() and g2["note"].str.contains("6.9").all()
    held, ins = (check_summary(checks[checks["fold"] == f]) for f in ("group held out", "in-sample"))
    assert held["sd"] >= 0.9 * ins["sd"]                      # unseen surfaces are not predicted better
    table = pd.read_csv(out / "tables" / "criterion_check.csv")
    assert {"error [°]", "δ measured [°]", "δ predicted [°]"} <= set(table.columns)
    md = (out / "tables" / "criterion_check.md").read_text()
    assert "largest miss" in md and "group held out" in md
    assert (out / "figures" / "criterion_check.png").is_file()

    model = load_criterion(out / "criterion.json")
    row = checks[(checks["fold"] == "in-sample") & checks["error_deg"].notna()].iloc[0]
    p = predict(model, row["friction_ps"], row["theta_a_deg_92"],
                float(res.points.set_index("physical_case").loc[row["physical_case"], "theta_a_deg_90"]),
                bool(row["flat_spaced"]))
    assert p.efficiency == pytest.approx(row["E_predicted"], rel=1e-6)


# ---- a paper's figures and tables (issue 32 item 5) -------------------------------------------------
def test_intervals_respect_their_quantity():
    """Below 3 seeds no interval; a positive ratio's never below 0 (log scale); an angle's within
    [−90°, 90°]; at the study's scatter (6 % at 3 seeds) the log interval's ends lie within 1.5 % of
    Student t's."""
    from interphase.analysis.ensemble import t_interval, values_interval

    assert all(np.isnan(values_interval([0.30, 0.50], "tan_delta")))            # two seeds: none
    wide = [0.05, 0.45, 0.9]
    assert t_interval(np.array(wide))[0] < 0 < values_interval(wide, "tan_delta")[0]
    lo, hi = values_interval(wide, "tan_delta")
    assert lo < np.mean(wide) < hi
    lo, hi = values_interval([60.0, 85.0, 89.5], "theta_r_surface_deg")
    assert t_interval(np.array([60.0, 85.0, 89.5]))[1] > 90 and hi == 90.0 and lo < 78.2
    tight = [0.50, 0.53, 0.47]                                                  # 6 % scatter
    assert np.allclose(values_interval(tight, "tan_delta"), t_interval(np.array(tight)), rtol=0.015)


QUICK = ROOT / "campaigns" / "quick.toml"


@pytest.fixture(scope="module")
def quick_shaped_report(tmp_path_factory):
    """campaigns/quick.toml's plan (16 surfaces × 2 seeds, 2 box seeds) restored from a synthetic
    summaries table and curves (report.synthetic.synthetic_restore: no engine), then reported; every
    figure is checked as it is saved: {stem: what the checks found}."""
    from interphase.report import figures as F
    from interphase.report.synthetic import synthetic_restore

    tmp = tmp_path_factory.mktemp("quickshape")
    toml = tmp / "quick.toml"
    text = "\n".join(line for line in QUICK.read_text().splitlines() if not line.startswith("output ="))
    toml.write_text(text.replace('name = "quick"', f'name = "quick"\noutput = "{tmp / "runs"}"', 1))
    table, _ = synthetic_restore(toml, tmp / "record", seed=3)
    assert main(["run", str(toml), "--restore", str(table)]) == 0
    seen, original = {}, F.save

    def checking_save(fig, folder, stem):
        legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None] + list(fig.legends)
        seen[stem] = {"overflow": F.legend_overflow(fig), "size": tuple(fig.get_size_inches()),
                      "legend_entries": [len(leg.get_texts()) for leg in legends],
                      "panels": sum(ax.get_visible() for ax in fig.axes)}
        return original(fig, folder, stem)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(F, "save", checking_save)
        assert main(["report", str(toml), "--out", str(tmp / "report"), "--bootstrap", "20"]) == 0
    return tmp / "report", seen


def test_two_seeds_give_no_interval_and_the_tables_say_so(quick_shaped_report):
    out, _ = quick_shaped_report
    ens = pd.read_csv(out / "tables" / "ensembles.csv")
    assert len(ens) == 16 and (ens["seeds"] == 2).all()
    for c in ("tan_delta", "tan_phi", "E", "theta_r"):
        lo = ens[f"{c}_lo" if c != "theta_r" else "theta_r_lo"]
        assert lo.isna().all(), c
    assert ens["note"].str.contains("fewer than 3 seeds").all()
    assert (ens["tan_delta"] > 0).all()
    res = pd.read_csv(out / "tables" / "results_quick.csv")
    assert res["tan δ 95%"].isna().all() and res["θr 95%"].isna().all()
    html = (out / "index.html").read_text()
    assert "fewer than 3 seeds" in html and "none with fewer than 3 seeds" in html


def test_a_figure_with_nothing_to_draw_is_left_out_and_the_page_says_why(quick_shaped_report):
    out, seen = quick_shaped_report
    assert not (out / "figures" / "fig6_9.png").exists() and "fig6_9" not in seen
    html = (out / "index.html").read_text()
    part = html[html.index('id="not-drawn"'):]
    assert "Fig. 6.9" in part and "flat-spaced" in part and "n = 0" in part


def test_every_legend_lies_inside_its_image(quick_shaped_report):
    _, seen = quick_shaped_report
    assert {"fig6_3", "fig6_8", "fig6_10a", "curves_quick", "curves_box"} <= set(seen)
    assert {stem: s["overflow"] for stem, s in seen.items() if s["overflow"]} == {}


def test_curves_are_faceted_by_friction_with_a_legend_per_panel(quick_shaped_report):
    out, seen = quick_shaped_report
    c = seen["curves_quick"]
    assert c["panels"] == 2 and c["legend_entries"] == [8, 8]       # 8 surfaces per friction, seeds share one
    assert seen["curves_box"]["legend_entries"] == [1]


def test_pngs_are_300_dpi_beside_their_pdf(quick_shaped_report):
    from PIL import Image

    out, seen = quick_shaped_report
    for stem in ("fig6_8", "fig6_10a", "curves_quick"):
        with Image.open(out / "figures" / f"{stem}.png") as im:
            assert im.info["dpi"] == pytest.approx((300, 300), abs=0.5)
            w, h = seen[stem]["size"]
            assert im.size == (round(300 * w), round(300 * h))
            assert np.asarray(im.convert("L")).std() > 5                 # not a blank image
        assert (out / "figures" / f"{stem}.pdf").stat().st_size > 1000


def test_figure_key_entries_all_look_different():
    from interphase.report.figures import key_handles

    pts = synthetic_summaries(60, seed=2)
    pts = pts[pts["test"] == "interface"]
    handles = key_handles(pts)

    def look(h):
        if hasattr(h, "get_marker"):
            return ("marker", h.get_marker(), str(h.get_markerfacecolor()), str(h.get_color()))
        return ("patch", tuple(h.get_facecolor()), tuple(h.get_edgecolor()))

    looks = [look(h) for h in handles]
    assert len(handles) == 3 + 5 + 2 and len(set(looks)) == len(looks)


def test_error_bars_stay_inside_the_axes(tmp_path):
    """Three seeds a case with a wide scatter: every 95 % bar whole inside the axes."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    from interphase.analysis.correlations import prepare_points, seed_ensemble
    from interphase.report import figures as F

    rng = np.random.default_rng(4)
    rows = []
    for i in range(8):
        for s in range(3):
            rows.append(dict(case_id=f"c{i}s{s}", group="g1", label=f"iface-rt{i}-s{s + 1}", role="interface",
                             test="interface", pair_id=f"b{s}", friction_ps=0.2, gradation="poly", sr=0.0,
                             profile_kind="sawtooth", theta_a_deg_92=6.0 * i, theta_a_deg_90=6.0 * i,
                             theta_r_surface_deg=min(89.0, 10 + 10 * i + rng.normal(0, 8)),
                             peak_stress_ratio=abs(0.3 + 0.02 * i + rng.normal(0, 0.08)), seed=s + 1))
    rows += [dict(case_id=f"b{s}", group="box", label=f"box-s{s + 1}", role="box", test="box",
                  peak_stress_ratio=0.55 + 0.02 * s, seed=s + 1) for s in range(3)]
    points = seed_ensemble(prepare_points(pd.DataFrame(rows))).points
    assert (points["theta_r_surface_deg_hi"] <= 90).all() and (points["peak_stress_ratio_lo"] > 0).all()
    fig, ax = plt.subplots()
    colour, marker = F._styles(points)
    F.scatter(ax, points, "theta_r_surface_deg", "efficiency", colour, marker)
    F.fit_view(ax, points, "theta_r_surface_deg", "efficiency")
    segs = [seg for c in ax.collections if isinstance(c, LineCollection) for seg in c.get_segments()]
    assert segs
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    pts = np.concatenate(segs)
    assert (pts[:, 0] >= x0).all() and (pts[:, 0] <= x1).all() and (pts[:, 1] >= y0).all() and (pts[:, 1] <= y1).all()
    plt.close(fig)


def _need(name: str) -> str:
    from tests.conftest import need_binary

    return need_binary(name)


def test_latex_tables_compile_and_read_back(quick_shaped_report, tmp_path):
    """Every fragment is plain ASCII; tables_preview.tex compiles with Debian's texlive-latex-base and
    -recommended (booktabs, graphicx, geometry), with outline fonts only; pdftotext finds the Greek
    headers, the numbers and the notes."""
    import shutil
    import subprocess

    pdflatex, pdftotext, pdffonts = (_need(b) for b in ("pdflatex", "pdftotext", "pdffonts"))
    out, _ = quick_shaped_report
    work = tmp_path / "tables"
    shutil.copytree(out / "tables", work, ignore=shutil.ignore_patterns("*.parquet", "*.csv", "*.md"))
    for tex in work.glob("*.tex"):
        tex.read_bytes().decode("ascii")                     # raises on any raw Unicode
    run = subprocess.run([pdflatex, "-interaction=nonstopmode", "-halt-on-error", "-no-shell-escape",
                          "tables_preview.tex"], cwd=work, capture_output=True, text=True, timeout=120)
    log = (work / "tables_preview.log").read_text(errors="replace")
    assert run.returncode == 0, log[-3000:]
    assert "Missing character" not in log and "Undefined control sequence" not in log
    fonts = subprocess.run([pdffonts, "tables_preview.pdf"], cwd=work, capture_output=True, text=True).stdout
    assert "Type 3" not in fonts                             # no bitmap font
    text = " ".join(subprocess.run([pdftotext, "tables_preview.pdf", "-"], cwd=work, capture_output=True,
                                   text=True).stdout.split())
    for phrase in ("Seed ensembles", "tan δ peak", "θr surface", "Bilinear correlations", "fewer than 3 seeds",
                   "interphase-dem", "none with fewer than 3 seeds"):
        assert phrase in text, phrase
    ens = pd.read_csv(out / "tables" / "ensembles.csv")
    assert f"{ens['tan_delta'].iloc[0]:.3f}" in text and f"{ens['E'].iloc[-1]:.3f}" in text


CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run", "--hide-scrollbars")

#: appended to a copy of the page: after load, what the layout is, as JSON in <pre id="layout-check">
LAYOUT_JS = """<script>
window.addEventListener('load', () => {
  const doc = document.documentElement;
  const out = {pageOverflow: doc.scrollWidth - doc.clientWidth, tables: [], images: []};
  for (const t of document.querySelectorAll('table')) {
    const box = t.parentElement, row = t.rows[0], last = row.cells[row.cells.length - 1];
    out.tables.push({title: (box.previousElementSibling || {}).textContent || '', width: t.scrollWidth,
                     box: box.clientWidth, scrollBox: ['auto', 'scroll'].includes(getComputedStyle(box).overflowX),
                     lastRight: last.getBoundingClientRect().right, boxRight: box.getBoundingClientRect().right});
  }
  for (const img of document.images)
    out.images.push({src: img.getAttribute('src'), w: img.naturalWidth, h: img.naturalHeight, shown: img.clientWidth});
  const pre = document.createElement('pre');
  pre.id = 'layout-check';
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
});
</script>"""


def test_report_page_in_headless_chromium(quick_shaped_report, tmp_path):
    """The page at 1280 px: nothing scrolls the page sideways, every table sits in a scroll box and
    fits it (its last column, the notes, inside the box), every figure image loads with pixels; a
    screenshot of the top of the page is not blank."""
    import json
    import subprocess

    from PIL import Image

    chromium = _need("chromium")
    out, _ = quick_shaped_report
    page = out / "layout_check.html"
    page.write_text((out / "index.html").read_text().replace("</body>", LAYOUT_JS + "</body>"))
    common = [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'profile'}", "--virtual-time-budget=5000"]
    try:
        dom = subprocess.run([*common, "--window-size=1280,900", "--dump-dom", page.as_uri()], capture_output=True,
                             text=True, timeout=120).stdout
        shot = tmp_path / "page.png"
        subprocess.run([*common, "--window-size=1280,2400", f"--screenshot={shot}", (out / "index.html").as_uri()],
                       capture_output=True, timeout=120, check=True)
    finally:
        page.unlink()
    m = re.search(r'<pre id="layout-check">([^<]*)</pre>', dom)
    assert m, dom[-2000:]
    import html as _html
    layout = json.loads(_html.unescape(m.group(1)))
    assert layout["pageOverflow"] <= 0
    assert len(layout["tables"]) >= 3                      # inputs, ensembles, correlations
    for t in layout["tables"]:
        assert t["scrollBox"], t["title"]
        assert t["width"] <= t["box"] + 1 and t["lastRight"] <= t["boxRight"] + 1, t
    figures = [f.name for f in (out / "figures").glob("*.png")]
    assert sorted(i["src"].split("/")[-1] for i in layout["images"]) == sorted(figures)
    assert all(i["w"] > 500 and i["h"] > 300 and i["shown"] > 300 for i in layout["images"]), layout["images"]
    with Image.open(shot) as im:
        assert im.size == (1280, 2400) and np.asarray(im.convert("L")).std() > 10
