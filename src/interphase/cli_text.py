"""The text of `campaign status`: its table of cases, its seed rounds and lines wrapped between
words. Formatting only: it reads what the API returns and imports nothing of the package."""

from __future__ import annotations


def status_text(campaign, df, width: int = 80) -> list[str]:
    """`campaign status`'s lines of a campaign (.name, .output, .output_from) and its status table
    (interphase.api.status): the counts, the runs folder, one row per case, what is wrong with failed
    or corrupt ones, one line per kind of stale, and the seed rounds."""
    counts = df["status"].value_counts().to_dict()
    lines = [_wrap(f"{campaign.name}: " + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())), width),
             _wrap(f"runs folder {campaign.output} ({campaign.output_from})", width), *status_rows(df, width)]
    bad = df[df["status"].isin(("corrupt", "failed"))]
    for r in bad.itertuples():       # what is wrong and the fix, under the table (wrapped, not cut)
        if isinstance(r.message, str) and r.message:
            lines.append(_wrap(f"{str(r.case_id)[:8]} {r.status}: {r.message}", width))
    stale = df[df["status"] == "stale"]
    for kind, rows in stale.groupby("cause"):   # one line per kind: a recipe change makes every case stale
        lines.append(_wrap(f"{len(rows)} stale ({kind}), e.g. {str(rows['case_id'].iloc[0])[:8]}: "
                           f"{rows['message'].iloc[0]}", width))
    seeds = df.attrs.get("seeds")
    return lines + (seed_rows(seeds, width) if seeds is not None else [])


def seed_rows(seeds, width: int = 80) -> list[str]:
    """Sequential seeds ([seeds]): one line per physical case: seeds finished / asked for, the
    interval of the target quantity at the last round judged and its half-width, the state."""
    if seeds.empty:
        return []
    r0 = seeds.iloc[0]
    lines = [f"seeds: target ± {r0.target:g} in {r0.quantity}, cap {int(r0.cap)} seeds",
             f"{'case':<{width - 58}} {'seeds':>9} {r0.quantity:>7} {'95 % interval':>15} {'± half':>7}  state"]
    room = width - 58
    for r in seeds.itertuples():
        name = f"{r.group}/{r.case}"
        name = name if len(name) <= room else "…" + name[len(name) - room + 1:]
        ival = f"{r.lo:.3f}–{r.hi:.3f}" if r.lo == r.lo and r.hi == r.hi else "–"
        lines.append(f"{name:<{room}} {f'{r.finished}/{r.wanted}':>9} {r.value:>7.3f} {ival:>15} "
                     f"{r.halfwidth:>7.3f}  {r.state}")
    return lines


def status_rows(df, width: int = 80) -> list[str]:
    """One line per case in `width` columns: short id, engine, label, status, cause. A label too long
    for its column loses the start it shares with the other labels (`…` in its place), then, if
    still too long, more of its start: the end, which tells cases apart (`-mu0.2-poly-s1`), stays.
    Full ids, labels and messages: `campaign status --json`."""
    labels = [str(x) for x in df["label"]] if len(df) else []
    room = width - (8 + 1 + 8 + 1 + 1 + 11 + 1 + 14)
    common = _common_prefix(labels) if len(labels) > 1 else ""
    lines = [f"{'id':<8} {'engine':<8} {'label':<{room}} {'status':<11} cause"]
    for r in df.itertuples():
        label = str(r.label)
        if len(label) > room and common:
            label = "…" + label[len(common):]
        if len(label) > room:
            label = "…" + label[len(label) - room + 1:]
        cause = r.cause if isinstance(r.cause, str) else ""
        lines.append(f"{str(r.case_id)[:8]:<8} {str(r.engine)[:8]:<8} {label:<{room}} {str(r.status)[:11]:<11} "
                     f"{cause[:14]}".rstrip())
    return lines


def _common_prefix(labels: list[str]) -> str:
    """The start every label shares, cut back to a '-' (whole label parts only)."""
    import os

    prefix = os.path.commonprefix(labels)
    return prefix[:prefix.rfind("-") + 1] if "-" in prefix else ""


def _wrap(text: str, width: int) -> str:
    """`text` wrapped between words only: a path or a command longer than the line stays whole (a
    terminal folds it; copied, it still works), and continuation lines are indented."""
    import textwrap

    return textwrap.fill(text, width=width, break_long_words=False, break_on_hyphens=False,
                         subsequent_indent="  ")
