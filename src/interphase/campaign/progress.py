"""Progress display of a campaign run: a live rich table on a terminal, plain lines otherwise.

Per case: state (queued, running, done, failed, killed, interrupted), elapsed time and, while it runs,
how far its engine has got (`stage_of`: e.g. "shear 40 %", read from the case's own files by
engines.progress); overall: counts and an ETA = remaining cases × mean duration of the cases
finished in this run / parallel slots. Plain lines say a running case's stage within TICK seconds of
its start, then again at each new stage and each further tenth of it.
"""

from __future__ import annotations

import sys
import threading
import time

TICK = 1.0                  # [s] how often a running case's stage is read (plain lines; a few tail bytes)


def _fmt_s(seconds: float | None) -> str:
    if seconds is None or seconds != seconds:
        return "—"
    seconds = int(round(seconds))
    h, rem = divmod(seconds, 3600)
    m, s = divmod(rem, 60)
    return f"{h}h{m:02d}m" if h else (f"{m}m{s:02d}s" if m else f"{s}s")


class Progress:
    """Receives executor events; `live` (rich) if the stream is a terminal, else one line per event."""

    STYLE = {"queued": "dim", "running": "cyan", "done": "green", "failed": "red", "killed": "magenta",
             "interrupted": "yellow", "pending": "dim"}

    def __init__(self, items, slots: int, stream=None, live: bool | None = None, title: str = "",
                 stage_of=None):
        self.stream = stream or sys.stdout
        self.stage_of = stage_of            # case id → its running engine's Stage (engines.progress), or None
        self._said: dict[str, tuple] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._ticker = None
        self.items = {p.case_id: p for p in items}
        self.state = {cid: "queued" for cid in self.items}
        self.t0: dict[str, float] = {}
        self.elapsed: dict[str, float] = {}
        self.cause: dict[str, str] = {}
        self.slots = max(1, slots)
        self.title = title
        self.started = time.monotonic()
        self.live = self.stream.isatty() if live is None else live
        self._live = None

    # ---- numbers ---------------------------------------------------------------------------
    def counts(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for s in self.state.values():
            out[s] = out.get(s, 0) + 1
        return out

    def eta(self) -> float | None:
        durations = [v for v in self.elapsed.values() if v]
        left = sum(1 for s in self.state.values() if s in ("queued", "running"))
        if not left:
            return 0.0
        if not durations:
            return None
        mean = sum(durations) / len(durations)
        running_left = sum(max(0.0, mean - (time.monotonic() - self.t0[c]))
                           for c, s in self.state.items() if s == "running" and c in self.t0)
        queued = sum(1 for s in self.state.values() if s == "queued")
        return (running_left + queued * mean) / self.slots

    def headline(self) -> str:
        c = self.counts()
        parts = [f"{c.get(k, 0)} {k}" for k in ("done", "running", "queued", "failed", "killed", "interrupted")
                 if c.get(k)]
        return (f"{self.title} {sum(c.values())} cases: " + ", ".join(parts)
                + f" | elapsed {_fmt_s(time.monotonic() - self.started)}, ETA {_fmt_s(self.eta())}")

    # ---- events ----------------------------------------------------------------------------
    def __enter__(self):
        if self.live:
            from rich.console import Console
            from rich.live import Live

            self._live = Live(self._table(), console=Console(file=self.stream), refresh_per_second=4,
                              get_renderable=self._table)
            self._live.__enter__()
        else:
            self._line(f"{self.title} {len(self.items)} cases to run, {self.slots} at a time")
            if self.stage_of is not None:
                self._ticker = threading.Thread(target=self._tick, daemon=True)
                self._ticker.start()
        return self

    def _tick(self) -> None:
        while not self._stop.wait(TICK):
            for cid in [c for c, s in list(self.state.items()) if s == "running"]:
                try:
                    stage = self.stage_of(cid)
                except Exception:          # a half-written file: the next tick reads it again
                    continue
                if stage is None:
                    continue
                key = (stage.name, None if stage.share is None else int(10 * stage.share))
                if self._said.get(cid) != key:
                    self._said[cid] = key
                    p = self.items.get(cid)
                    el = time.monotonic() - self.t0.get(cid, time.monotonic())
                    self._line(f"  at     {cid}  {p.label if p else ''}  {stage.text()}  ({_fmt_s(el)})")

    def __exit__(self, *exc):
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join(timeout=2 * TICK)
        if self._live is not None:
            self._live.__exit__(*exc)
            self._live = None
        self._line(self.headline())

    def _line(self, text: str) -> None:
        with self._lock:
            print(text, file=self.stream, flush=True)

    def event(self, kind: str, case_id: str, info: dict) -> None:
        p = self.items.get(case_id)
        label = p.label if p else ""
        if kind == "note":
            self._line(f"  note   {info.get('message', '')}")
            return
        if kind == "started":
            self.state[case_id] = "running"
            self.t0[case_id] = time.monotonic()
            if not self.live:
                where = f"job {info['slurm_job']}" if info.get("slurm_job") else f"pid {info.get('pid')}"
                self._line(f"  start  {case_id}  {label}  ({where})")
        elif kind == "finished":
            status = info.get("status", "failed")
            self.state[case_id] = status if status != "pending" else "queued"
            if status == "pending":
                return
            el = info.get("elapsed")
            if el is None and case_id in self.t0:
                el = time.monotonic() - self.t0[case_id]
            if status == "done":
                self.elapsed[case_id] = el or 0.0
            if info.get("cause"):
                self.cause[case_id] = info["cause"]
            if not self.live:
                c = self.counts()
                n = sum(c.get(k, 0) for k in ("done", "failed", "killed", "interrupted"))
                msg = str(info.get("message") or "")
                tag = f"[{info.get('cause')}]"
                msg = msg[len(tag):].lstrip() if msg.startswith(tag) else msg    # EngineError says its cause
                extra = f" {tag} {msg[:240]}" if status != "done" else ""
                self._line(f"  {status:<11} {case_id}  {label}  {_fmt_s(el)}  ({n}/{len(self.items)}, "
                           f"ETA {_fmt_s(self.eta())}){extra}")

    def _stage(self, cid: str):
        if self.stage_of is None:
            return None
        try:
            return self.stage_of(cid)
        except Exception:                  # a half-written file: the next refresh reads it again
            return None

    def _table(self):
        from rich.table import Table

        t = Table(title=self.headline(), expand=False)
        for col in ("case", "label", "state", "time", "progress", "cause"):
            t.add_column(col)
        order = {"running": 0, "failed": 1, "killed": 1, "interrupted": 1, "queued": 2, "done": 3}
        shown = sorted(self.items, key=lambda c: (order.get(self.state[c], 4), self.items[c].index))[:30]
        for cid in shown:
            s = self.state[cid]
            el = (time.monotonic() - self.t0[cid]) if s == "running" and cid in self.t0 else self.elapsed.get(cid)
            stage = self._stage(cid) if s == "running" else None
            t.add_row(cid, self.items[cid].label, f"[{self.STYLE.get(s, '')}]{s}[/]", _fmt_s(el),
                      stage.text() if stage else "", self.cause.get(cid, ""))
        if len(self.items) > len(shown):
            t.caption = f"… {len(self.items) - len(shown)} more"
        return t
