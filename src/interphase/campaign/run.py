"""`campaign run` and `campaign status`: plan, lock, skip what is finished, execute, index.

    run_campaign("campaigns/group1.toml", executor="slurm")   → RunReport (counts; exit code)

`engines` (names or engines.base.EngineSpec values; default: the file's names) are made into
values once, by the plan; every planned case carries its engine's value to the executor.

The campaign lock (filelock) makes a second `campaign run` of the same campaign stop with a clear
message. Finished cases (DONE) are never rerun; failed and SLURM-killed ones only with
`rerun_failed`, and so are corrupt ones (DONE, but the folder does not verify: store.verify_folder;
their DONE is removed first so that the runner cleans the folder); interrupted and incomplete ones
always (they never finished).

A case is *stale* (`find_stale`) when its finished result is not of the current recipe or engine
build: (recipe) no folder of this recipe's id, but a finished one of the same label and engine under
another recipe (a recipe change gives new ids); (engine build) finished, but by another build of the
engine than this machine's, when this machine's can be told. Stale cases are kept as they are and
listed; `rerun_stale` runs them: under this recipe in a new folder (the old one stays), or, for an
engine build, again in the same folder after the old one is moved to `<output>/.superseded/`.

A round of a run is a Selection (`select`: what each planned case gets — run, finished, kept, stale —
decided from the index and printed before anything is touched), then its execution (`_execute`).
"""

from __future__ import annotations

import math
import os
import signal
import sqlite3
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from interphase.campaign import store as st
from interphase.campaign.executors import STOP_FILE, LocalExecutor, SlurmExecutor, StopAsked, Task
from interphase.campaign.plan import PlannedCase, estimate_seconds, plan, time_limit_minutes
from interphase.campaign.progress import Progress
from interphase.campaign.runner import Interrupted
from interphase.campaign.schema import EXECUTORS, Campaign, load_campaign
from interphase.errors import InputError


@dataclass
class RunReport:
    campaign: str
    output: Path
    planned: int = 0
    skipped_done: int = 0
    skipped_failed: int = 0
    ran: int = 0
    statuses: dict = field(default_factory=dict)      # case id → status of this run
    interrupted: bool = False
    stopped: str | None = None                        # why the run stopped early (not a user's Ctrl-C)
    dry_run: bool = False                             # nothing ran: what would run was said

    def count(self, status: str) -> int:
        return sum(1 for s in self.statuses.values() if s == status)

    @property
    def exit_code(self) -> int:
        """0: every case of the campaign is finished, or a dry run; 1: some failed or were killed, or the
        run stopped itself (a full disk); 130: interrupted."""
        if self.dry_run:
            return 0
        if self.stopped:
            return 1
        if self.interrupted:
            return 130
        return 0 if all(s == "done" for s in self.statuses.values()) and not self.skipped_failed else 1


def _state(store: st.CampaignStore, indexed: dict, case_id: str) -> str:
    """A case's state: its folder's, corrupt where the (reconciled) index found a DONE folder corrupt."""
    folder = store.case_folder(case_id)
    fs = st.folder_status(folder) if folder.exists() else "pending"
    return "corrupt" if fs == "done" and indexed.get(case_id) == "corrupt" else fs


@dataclass(frozen=True)
class Stale:
    """Why a planned case's finished result is not current: kind 'recipe' or 'engine build'."""

    kind: str
    message: str
    run_id: str            # the folder of the finished run it refers to


def engine_builds(engines) -> dict[str, str | None]:
    """{engine name: the build this machine runs} of `engines` (EngineSpecs); None where it cannot
    be told (not installed, banner unreadable): nothing is judged stale against it, so a laptop
    without engines flags nothing."""
    out = {}
    for spec in engines:
        if spec.name not in out:
            v = spec.build().version()
            out[spec.name] = None if v in ("not-installed", "unknown") else v
    return out


def find_stale(planned: list[PlannedCase], rows, builds: dict) -> dict[str, Stale]:
    """{case id: Stale} of the planned cases whose finished result is of another recipe or engine
    build. `rows`: the index (CampaignStore.status(), every folder); `builds`: engine_builds()."""
    ids = {p.case_id for p in planned}
    done = rows[rows["status"] == "done"]
    earlier = {}
    for r in done[~done["case_id"].isin(ids)].sort_values("finished", na_position="first").itertuples():
        earlier[(r.label, r.engine)] = r           # the latest finished run of another recipe
    by_id = {r.case_id: r for r in rows.itertuples()}
    out = {}
    for p in planned:
        row = by_id.get(p.case_id)
        status = row.status if row is not None else "pending"
        old = earlier.get((p.label, p.engine))
        if status == "pending" and old is not None and old.recipe_id != p.recipe_id:
            out[p.case_id] = Stale("recipe", f"finished under recipe {old.recipe_id} (folder {old.case_id}), not "
                                   f"this version's {p.recipe_id}: kept; `campaign run --rerun-stale` runs it under "
                                   "this recipe", old.case_id)
        elif status == "done" and builds.get(p.engine) and isinstance(row.engine_version, str) \
                and row.engine_version != builds[p.engine]:
            out[p.case_id] = Stale("engine build", f"run by {row.engine_version}; this machine has "
                                   f"{builds[p.engine]}: `campaign run --rerun-stale` runs it again (the old folder "
                                   "is kept in .superseded/)", p.case_id)
    return out


@dataclass
class Selection:
    """What a round of `campaign run` does with each planned case, decided from the index before
    anything is touched (`select`): printed (`lines`), then executed. `run`: the cases to run;
    `done`: finished; `kept`: failed, killed or corrupt, kept without rerun_failed; `kept_stale`:
    stale (find_stale), kept without rerun_stale; `states`: {case id: folder state} of the kept
    ones; `corrupt`: ids of the cases to run whose finished folder is corrupt (discarded first)."""

    run: list[PlannedCase]
    done: list[PlannedCase]
    kept: list[PlannedCase]
    kept_stale: list[PlannedCase]
    stale: dict[str, Stale]
    states: dict[str, str]
    corrupt: set[str]

    def statuses(self) -> dict[str, str]:
        """{case id: status} of the cases that do not run: an earlier recipe's result is not this
        recipe's ('stale'); another engine build's is ('done')."""
        out = {p.case_id: "done" for p in self.done} | {p.case_id: self.states[p.case_id] for p in self.kept}
        return out | {p.case_id: "stale" if self.stale[p.case_id].kind == "recipe" else "done" for p in self.kept_stale}

    def lines(self, name: str, executor: str, output) -> list[str]:
        """What `campaign run` says before it runs anything."""
        n = len(self.run) + len(self.done) + len(self.kept) + len(self.kept_stale)
        out = [f"campaign {name}: {n} cases, {len(self.done)} finished, {len(self.kept)} failed (kept; "
               "--rerun-failed reruns them), " + (f"{len(self.kept_stale)} stale (kept; --rerun-stale reruns "
                                                  "them), " if self.kept_stale else "")
               + f"{len(self.run)} to run [{executor}] → {output}"]
        corrupt = sum(1 for p in self.kept if self.states[p.case_id] == "corrupt")
        if corrupt:
            out.append(f"campaign {name}: {corrupt} finished case(s) are corrupt and not used (see `campaign "
                       "status`); --rerun-failed reruns them")
        kinds = sorted({self.stale[p.case_id].kind for p in self.kept_stale})
        if kinds:
            out.append(f"campaign {name}: stale = finished under another {' or '.join(kinds)} "
                       "(`campaign status` lists them)")
        return out


def select(planned: list[PlannedCase], store: st.CampaignStore, builds: dict, rerun_failed: bool,
           rerun_stale: bool) -> Selection:
    """The Selection of `planned` after store.reconcile(); reads the index, writes nothing."""
    stale = find_stale(planned, store.status(), builds)
    indexed = store.statuses()
    sel = Selection([], [], [], [], stale, {}, set())
    for p in planned:
        fs = _state(store, indexed, p.case_id)
        if p.case_id in stale:
            (sel.run if rerun_stale else sel.kept_stale).append(p)
        elif fs == "done":
            sel.done.append(p)
        elif fs in st.KEPT_STATUSES and not rerun_failed:
            sel.kept.append(p)
            sel.states[p.case_id] = fs
        else:
            sel.run.append(p)
            if fs == "corrupt":
                sel.corrupt.add(p.case_id)
    return sel


def _supersede(store: st.CampaignStore, case_id: str) -> Path:
    """Move a finished folder out of the campaign (to .superseded/<id>-<time>/) before it is run again."""
    dest = store.root / ".superseded" / f"{case_id}-{int(time.time())}"
    dest.parent.mkdir(exist_ok=True)
    os.replace(store.case_folder(case_id), dest)
    store.set_status(case_id, "pending")
    return dest


def _slots(campaign: Campaign, executor: str, jobs: int | None) -> int:
    if executor == "local":
        n = jobs if jobs is not None else campaign.execution.jobs
        return n if n and n > 0 else (os.cpu_count() or 1)
    return campaign.execution.max_concurrent


#: above this many cases a run, or a dry run's full listing and decks, asks for `yes` (--yes)
LARGE = 10_000
#: planned cases a dry run shows before its tallies
SAMPLE = 10


def run_campaign(path, *, engines=None, executor: str | None = None, jobs: int | None = None,
                 rerun_failed: bool = False, rerun_stale: bool = False, dry_run: bool = False, output=None,
                 restore=None, stream=None, live: bool | None = None, yes: bool = False,
                 render: bool = False, list_all: bool = False) -> RunReport:
    """Run what is not finished. `restore`: a summaries table whose rows of planned cases become
    finished folders first (interphase.campaign.restore), so that only the rest runs. `engines`:
    names or EngineSpecs instead of the file's engine names (`--engine`; a test's engine values).

    The count comes first, before anything is planned: a campaign of more than LARGE cases is
    run (or fully listed by a dry run) only with `yes`. A dry run prints the count, a sample of
    SAMPLE cases and the tallies; it writes decks only with `render`, lists every case only with
    `list_all`."""
    stream = stream or sys.stdout
    campaign = load_campaign(path, output=output)
    executor = executor or campaign.execution.executor
    if executor not in EXECUTORS:
        raise InputError(f"unknown executor {executor!r}", where="--executor", fix=f"use one of {', '.join(EXECUTORS)}")
    if jobs is not None and jobs < 0:
        raise InputError(f"must be ≥ 0 (0 = one per core), got {jobs}", where="--jobs")
    n_engines = len(engines) if engines else len(campaign.engines)
    count = campaign.size * n_engines
    cap = "" if campaign.seeds is None else f" at most (sequential seeds: up to {campaign.seeds.max} per physical case)"
    print(f"campaign {campaign.name}: {campaign.size} case(s) in the sweeps × {n_engines} engine(s) = {count}{cap}, "
          f"plus their box tests; runs folder {campaign.output} ({campaign.output_from})", file=stream, flush=True)
    for w in campaign.warnings():
        print(f"warning: {w}", file=stream, flush=True)
    large = count > LARGE and not yes
    if large and not (dry_run and not (render or list_all)):
        raise InputError(f"{count} cases is more than {LARGE}", where=str(path),
                         fix="add --yes to plan them all (`--dry-run` alone shows the count and a sample)")
    if dry_run and (campaign.lazy or large):
        from interphase.campaign.plan import iter_plan

        return _dry_run(campaign, iter_plan(campaign, engines), executor, stream, report=RunReport(
            campaign.name, campaign.output), rerun_failed=rerun_failed, rerun_stale=rerun_stale, builds={},
            restore=restore, render=render, list_all=list_all, stop_after_sample=large)
    planned = plan(campaign, engines)
    report = RunReport(campaign.name, campaign.output, planned=len(planned))
    builds = engine_builds(p.engine_spec for p in planned)
    if dry_run:
        if campaign.seeds is not None:      # the next round: what the finished runs ask for now
            planned = _next_round(campaign, planned, stream)
        return _dry_run(campaign, planned, executor, stream, report, rerun_failed, rerun_stale, builds, restore,
                        render=render, list_all=list_all)

    store = st.CampaignStore(campaign.output, create=True)
    with store, store.lock("campaign run"):
        if (campaign.output / STOP_FILE).exists():      # it asked a run that has ended; this one goes on
            (campaign.output / STOP_FILE).unlink()
            print(f"campaign {campaign.name}: removed {campaign.output / STOP_FILE}, left from a run that had "
                  "ended", file=stream, flush=True)
        if restore is not None:
            from interphase.campaign.restore import describe, restore_runs

            print(f"campaign {campaign.name}: {describe(restore_runs(planned, store, restore, campaign.name))}",
                  file=stream, flush=True)
        rounds, last = 0, None
        while True:
            now = planned
            if campaign.seeds is not None:
                from interphase.campaign.sequential import this_round

                now, state = this_round(campaign, planned, store)
                rounds += 1
                _say_round(campaign, state, rounds, stream)
            report.planned = len(now)
            todo = _run_round(campaign, now, store, report, executor, jobs, stream, live, builds,
                              rerun_failed=rerun_failed and rounds <= 1, rerun_stale=rerun_stale and rounds <= 1)
            ids = {p.case_id for p in todo}
            if campaign.seeds is None or not todo or report.interrupted or ids == last:
                break       # no round left, or one that would only repeat the last (runs waiting)
            last = ids
    return report


def _run_round(campaign: Campaign, planned: list[PlannedCase], store: st.CampaignStore, report: RunReport,
               executor: str, jobs, stream, live, builds: dict, *, rerun_failed: bool, rerun_stale: bool) -> list:
    """Run what of `planned` is not finished (the campaign's lock held): its Selection, printed,
    then executed; returns the runs it started (empty: nothing was left to run). Statuses and counts
    go into `report`."""
    store.register(planned)
    store.reconcile(stale_running=True)   # we hold the lock: nothing of this campaign is running
    sel = select(planned, store, builds, rerun_failed, rerun_stale)
    report.skipped_done, report.skipped_failed = len(sel.done), len(sel.kept)
    report.statuses.update(sel.statuses())
    for line in sel.lines(campaign.name, executor, campaign.output):
        print(line, file=stream, flush=True)
    for p in sel.run:
        if p.case_id in sel.stale and sel.stale[p.case_id].kind == "engine build":
            dest = _supersede(store, p.case_id)
            print(f"rerun stale {p.case_id} ({p.label}): {sel.stale[p.case_id].message.split(':')[0]}; "
                  f"old folder → {dest}", file=stream, flush=True)
    for p in sel.run:
        if p.case_id in sel.corrupt:
            row = store.row(p.case_id) or {}
            print(f"rerun corrupt {p.case_id} ({p.label}): {row.get('message')}", file=stream, flush=True)
            st.discard_corrupt(store.case_folder(p.case_id), row.get("cause"), row.get("message"))
    if sel.run:
        _execute(campaign, sel.run, store, report, executor, jobs, stream, live, done=sel.done)
    return sel.run


def _execute(campaign: Campaign, todo: list[PlannedCase], store: st.CampaignStore, report: RunReport,
             executor: str, jobs, stream, live, done=()) -> None:
    """Run `todo` on the executor, recording every start and finish in the index and `report`
    (`done`: the finished runs that scale its time estimate); Ctrl-C, SIGTERM and a full disk stop it
    cleanly (report.interrupted)."""
    tasks = [Task(p.case, p.engine_spec, store.case_folder(p.case_id), p.meta(campaign.name)) for p in todo]
    for p in todo:
        store.set_status(p.case_id, "queued")
    slots = _slots(campaign, executor, jobs)
    if executor == "local":
        ex = LocalExecutor(slots, stop_file=campaign.output / STOP_FILE)
    else:
        ex = SlurmExecutor(campaign.output, partition=campaign.execution.partition, max_concurrent=slots,
                           job_name=f"interphase-{campaign.name}",
                           time_limit=lambda case: time_limit_minutes(case, campaign.execution.time_factor,
                                                                      campaign.execution.time_limit))
    progress = _progress(campaign, todo, store, min(slots, len(todo)), stream, live, done)

    index_trouble: list[str] = []

    def on_event(kind: str, cid: str, info: dict) -> None:
        try:
            if kind == "started":
                store.set_status(cid, "running", slurm_job=info.get("slurm_job"), started=time.time())
            elif kind == "finished":
                row = store.record_result(cid)
                report.statuses[cid] = row.get("status", info.get("status"))
        except sqlite3.OperationalError as exc:   # e.g. the disk is full: the folders stay the truth
            if not index_trouble:
                print(f"campaign {campaign.name}: the index could not be written ({exc}); the case folders are "
                      "the record, the next command re-reads them", file=stream, flush=True)
            index_trouble.append(cid)
            report.statuses[cid] = info.get("status")
        if kind == "finished" and info.get("status") != "pending":
            report.ran += 1
        progress.event(kind, cid, info)
        if kind == "finished" and info.get("cause") == "disk_full":
            # every case after this one would fill the same disk: stop, keep what is finished
            raise DiskFull(f"the disk is full (case {cid})")

    # SIGTERM (kill, a batch system) stops as cleanly as Ctrl-C; and SIGINT always interrupts: a
    # campaign started in the background of a script inherits SIGINT ignored, while its workers
    # do act on it (executors._local_task), which would stop their cases and run on with the rest
    old = signal.signal(signal.SIGTERM, _sigterm)
    old_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with progress:
            for stage in _stages(tasks, campaign.specimen_from):
                waiting = {t.case_id: s for t in stage if (s := _start_status(t.case)) != "done"}
                for t in stage:
                    if t.case_id in waiting:      # its specimen was not made: it stays pending
                        store.set_status(t.case_id, "pending")
                        print(f"wait {t.case_id} ({t.meta.get('label')}): the {t.case.start.engine} run it starts "
                              f"from, {t.case.start.case_id}, is {waiting[t.case_id]}; run the same command "
                              "again once it has finished", file=stream, flush=True)
                ready = [t for t in stage if t.case_id not in waiting]
                if ready:
                    ex.run(ready, on_event)
    except StopAsked as exc:
        report.interrupted = True
        print(f"campaign {campaign.name}: stopped as asked ({exc.reason}): the cases running then finished, "
              "no other started; run the same command again to go on.", file=stream, flush=True)
    except DiskFull as exc:
        report.interrupted, report.stopped = True, exc.reason
        print(f"campaign {campaign.name}: stopped: {exc.reason}. Running cases were stopped and recorded, "
              "finished ones are kept. Free some space and run the same command again.", file=stream, flush=True)
    except (KeyboardInterrupt, Interrupted):
        report.interrupted = True
        print(f"campaign {campaign.name}: interrupted; running cases were stopped and recorded, "
              "finished ones are kept. Run the same command again to go on.", file=stream, flush=True)
    finally:
        signal.signal(signal.SIGTERM, old)
        signal.signal(signal.SIGINT, old_int)
        try:
            store.reconcile([p.case_id for p in todo], stale_running=True)
        except sqlite3.OperationalError as exc:
            print(f"campaign {campaign.name}: the index could not be brought up to date ({exc}); the next "
                  "command re-reads the folders", file=stream, flush=True)
    for p in todo:
        report.statuses.setdefault(p.case_id, st.folder_status(store.case_folder(p.case_id)))


def _next_round(campaign: Campaign, planned: list[PlannedCase], stream) -> list[PlannedCase]:
    """The runs sequential seeds ask for now (campaign.sequential.this_round), read without the lock."""
    from interphase.campaign.sequential import rounds_of, wanted_ids

    if campaign.output.is_dir():
        with st.CampaignStore(campaign.output) as store:
            rounds = rounds_of(campaign, planned, store)
    else:
        rounds = rounds_of(campaign, planned, None)
    _say_round(campaign, rounds, 0, stream)
    want = wanted_ids(campaign.seeds, planned, rounds)
    return [p for p in planned if p.case_id in want]


def _say_round(campaign: Campaign, state: dict, n: int, stream) -> None:
    """One line per round of sequential seeds: cases still adding seeds, reached, capped."""
    counts: dict[str, int] = {}
    for r in state.values():
        counts[r.state] = counts.get(r.state, 0) + 1
    rule = campaign.seeds
    print(f"campaign {campaign.name}: seeds " + (f"round {n}" if n else "now") + f" (target ± {rule.halfwidth:g} in {rule.quantity}, "
          f"{rule.start}–{rule.max} seeds): " + ", ".join(f"{v} {k}" for k, v in sorted(counts.items()))
          + " physical case(s)", file=stream, flush=True)


def _stages(tasks: list[Task], specimen_from: str | None) -> list[list[Task]]:
    """The tasks in the order they may run: with specimen_from, that engine's runs first (the others
    start from their specimens), then the rest; else all at once."""
    if not specimen_from:
        return [tasks]
    first = [t for t in tasks if t.engine.name == specimen_from]
    return [s for s in (first, [t for t in tasks if t.engine.name != specimen_from]) if s]


def _start_status(case) -> str:
    """'done' when the case starts from its engine's own lattice or from a finished run, else that
    run's folder status."""
    if case.start is None:
        return "done"
    folder = Path(case.start.folder)
    return st.folder_status(folder) if folder.exists() else "not run"


def _sigterm(signum, frame):
    raise Interrupted("SIGTERM")


class DiskFull(Interrupted):
    """A case found the disk full: the run stops (the next case would too)."""


def _dry_run(campaign: Campaign, planned, executor: str, stream, report: RunReport,
             rerun_failed: bool = False, rerun_stale: bool = False, builds: dict | None = None,
             restore=None, *, render: bool = False, list_all: bool = False,
             stop_after_sample: bool = False) -> RunReport:
    """What a run would do, read one planned case at a time (`planned`: a list or iter_plan's
    generator): SAMPLE cases (every one with `list_all`), then the tallies per action. Decks are
    rendered under <output>/.dry-run/<case_id>/ only with `render`. Finished folders are verified
    (through the index, as `campaign status` does): a corrupt one is listed as kept, or as rerun with
    `rerun_failed`; a case without a folder whose id is a row of `restore` (a summaries table) as
    restored. `stop_after_sample`: a campaign over LARGE without --yes: the sample, then stop."""
    report.dry_run = True
    record = set()
    if restore is not None:
        from interphase.campaign.restore import restorable_ids

        record = restorable_ids(restore)

    root = campaign.output / ".dry-run"
    engines = {}
    indexed: dict = {}
    stale: dict = {}
    active = False                  # a `campaign run` holds the lock: its queued/running rows are real
    if campaign.output.is_dir() and isinstance(planned, list):
        with st.CampaignStore(campaign.output) as store:
            stale = find_stale(planned, store.status(), builds or {})
            indexed = store.statuses()
            active = store.run_active()
    total = f"{len(planned)} cases" if isinstance(planned, list) else "cases read one at a time"
    if campaign.seeds is not None:
        total = f"this round {total} (the seeds asked for now, with their box tests)"
    print(f"campaign {campaign.name} (dry run, {executor}): {total} → {campaign.output}", file=stream, flush=True)
    if active:
        print(f"  a `campaign run` is running in {campaign.output} now: another would be refused until it ends; "
              "`campaign stop` ends it after its running cases", file=stream, flush=True)
    tallies: dict[str, int] = {}
    n, seconds = 0, 0.0
    measured = [0, 0.0, 0.0]        # finished runs read here: count, their engine seconds, their estimate
    for p in planned:
        folder = campaign.output / p.case_id
        state, action = _dry_action(p.case_id, folder, indexed, stale, record, active, rerun_failed, rerun_stale)
        tallies[action] = tallies.get(action, 0) + 1
        n += 1
        left = action in ("run", "queued", "running") or action.startswith("rerun")   # what is left to run
        seconds += estimate_seconds(p.case) if left else 0.0
        if action == "skip (done)" and measured[0] < CALIBRATION_RUNS:
            _add_measured(measured, p, folder)
        if render and action == "run" and _start_status(p.case) == "done":
            if p.engine not in engines:
                engines[p.engine] = p.engine_spec.build()
            engines[p.engine].write_input(p.case, root / p.case_id)
        if n <= SAMPLE or list_all:
            limit = time_limit_minutes(p.case, campaign.execution.time_factor, campaign.execution.time_limit)
            shown = f"starts from {p.case.start.label()}; " if action == "run" and _start_status(p.case) != "done" \
                else ""
            print(f"  {action:<13} {p.case_id}  {p.engine:<8} {p.group:<8} {p.label}  "
                  f"[{shown}slurm limit {limit} min]", file=stream, flush=n == SAMPLE)
        if len(report.statuses) < LARGE:        # the report keeps a bounded record, not 10⁶ rows
            report.statuses[p.case_id] = state
        if stop_after_sample and n >= SAMPLE:
            print(f"  … (a sample of {SAMPLE}; more than {LARGE} cases: `--dry-run --yes` counts what would run, "
                  "`--render` writes their decks, `--list` lists every case)", file=stream, flush=True)
            return report
    if not list_all and n > SAMPLE:
        print(f"  … {n - SAMPLE} more (`--list` lists every case)", file=stream)
    report.planned = n
    print(f"{n} cases: " + ", ".join(f"{v} {k}" for k, v in sorted(tallies.items())), file=stream)
    print(_time_estimate(seconds, _slots(campaign, executor, None), measured), file=stream)
    print(f"decks rendered in {root}" if render else "no decks written (`--render` writes the decks of the cases "
          f"that would run, under {root})", file=stream, flush=True)
    return report


def _dry_action(cid: str, folder, indexed: dict, stale: dict, record: set, active: bool,
                rerun_failed: bool, rerun_stale: bool) -> tuple[str, str]:
    """(state, action) of one planned case in a dry run: what its folder says (the index's corrupt
    verdict, a restorable row, a live run's queued/running rows taken into account) and what a run
    would do with it."""
    state = st.folder_status(folder) if folder.exists() else "pending"
    if state == "done" and indexed.get(cid) == "corrupt":
        state = "corrupt"
    if cid in stale:
        return state, "rerun (stale)" if rerun_stale else "skip (stale)"
    if state == "pending" and not folder.exists() and cid in record:
        return "done", "restore"
    if state == "done":
        return state, "skip (done)"
    if state in st.KEPT_STATUSES:
        return state, f"rerun ({state})" if rerun_failed else f"skip ({state})"
    if active and indexed.get(cid) in ("queued", "running"):
        return state, indexed[cid]
    return state, "run"


#: finished runs of the campaign a dry run reads to scale its estimate (their case.json)
CALIBRATION_RUNS = 200


def _add_measured(measured: list, p: PlannedCase, folder: Path) -> None:
    """Add a finished run to `measured` (count, engine seconds, their estimate): its engine time, or
    for a restored run (no timings) the elapsed time its row brought."""
    meta = st.read_json(folder / st.CASE_JSON) or {}
    took = (meta.get("timings") or {}).get("execute") or meta.get("elapsed")
    if isinstance(took, (int, float)) and math.isfinite(took) and took > 0:
        measured[0] += 1
        measured[1] += took
        measured[2] += estimate_seconds(p.case)


def _progress(campaign: Campaign, todo: list, store, slots: int, stream, live, done=()) -> Progress:
    """The run's progress display, each running case's engine stage read from its folder; the
    time estimate printed before the first case starts, scaled by the finished runs `done` as the dry
    run's is."""
    measured = [0, 0.0, 0.0]
    for p in list(done)[:CALIBRATION_RUNS]:
        _add_measured(measured, p, store.case_folder(p.case_id))
    print(_time_estimate(sum(estimate_seconds(p.case) for p in todo), slots, measured), file=stream, flush=True)
    from interphase.engines.progress import liggghts_stage

    return Progress(todo, slots, stream=stream, live=live, title=campaign.name,
                    stage_of=lambda cid: liggghts_stage(store.case_folder(cid)))


def _time_estimate(seconds: float, slots: int, measured=(0, 0.0, 0.0)) -> str:
    """The dry run's estimate of what would run: engine time from plan.estimate_seconds (particle-steps
    at 1.5e6 per second on one core, docs/engines.md: a rough figure, often within a factor of 2),
    scaled by what the campaign's finished runs here took against their own estimate (`measured`:
    count, engine seconds, estimated seconds), which carries this machine's speed and the sharing of
    its cores by the runs' jobs."""
    if seconds <= 0:
        return "estimated time: nothing to run"
    n, took, est = measured
    scale = took / est if n and est > 0 else 1.0
    hours = seconds * scale / 3600.0
    how = (f"scaled by the {n} finished run(s) here, which took {scale:.2g}× their estimate" if n and est > 0 else
           "particle-steps at 1.5e6/s per core: a rough figure")
    return f"estimated time: {hours:.2g} slot-hour(s), about {hours / max(slots, 1):.2g} h on {slots} slot(s) ({how})"


def campaign_status(path, *, output=None, engines=None):
    """(Campaign, planned cases, status DataFrame of the planned cases; pending where never run).
    A stale case (find_stale) shows status 'stale', cause the kind, message the reason and fix.
    With [seeds] (sequential seeds) the planned cases are the runs the rounds asked for so far, and
    `df.attrs["seeds"]` is one row per physical case (campaign.sequential.rounds_frame); else None.
    `engines`: names or EngineSpecs instead of the file's engine names."""
    campaign = load_campaign(path, output=output)
    planned = plan(campaign, engines)
    seeds = None
    if campaign.seeds is not None:     # sequential seeds: the runs asked for so far, and each case's interval
        from interphase.campaign.sequential import rounds_frame, rounds_of, wanted_ids

        with (st.CampaignStore(campaign.output) if campaign.output.is_dir() else _nothing()) as store:
            rounds = rounds_of(campaign, planned, store)
        want = wanted_ids(campaign.seeds, planned, rounds)
        planned = [p for p in planned if p.case_id in want]
        seeds = rounds_frame(campaign.seeds, rounds)
    df = _status_frame(campaign, planned)
    df.attrs["seeds"] = seeds
    return campaign, planned, df


def _nothing():
    import contextlib

    return contextlib.nullcontext()


def _status_frame(campaign: Campaign, planned: list[PlannedCase]):
    """The status DataFrame of `planned`: see campaign_status."""
    import pandas as pd

    cols = ["case_id", "engine", "group", "label", "role", "status", "cause", "message", "elapsed", "attempts",
            "slurm_job"]
    if not campaign.output.is_dir():
        df = pd.DataFrame([{"case_id": p.case_id, "engine": p.engine, "group": p.group, "label": p.label,
                            "role": p.role, "status": "pending"} for p in planned], columns=cols)
        return df
    with st.CampaignStore(campaign.output) as store:
        store.register(planned)
        every = store.status()
    stale = find_stale(planned, every, engine_builds(p.engine_spec for p in planned))
    ids = [p.case_id for p in planned]
    df = every.set_index("case_id").reindex(ids).reset_index()
    for i, cid in enumerate(ids):
        if cid in stale:
            df.loc[i, ["status", "cause", "message"]] = ["stale", stale[cid].kind, stale[cid].message]
    return df[[c for c in cols + ["recipe_id", "engine_version"] if c in df.columns]]
