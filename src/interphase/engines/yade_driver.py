"""The YADE driver: one case run inside YADE, from the params.json that engines/yade.py writes.

The case folder's driver.py (run as `yade -n -x driver.py params.json`) puts this package on YADE's
sys.path and calls `main`. YADE runs the system python3, so this module imports only the standard
library at import time and YADE inside `main`; the pure functions below are tested without YADE.

Frame (docs/methods.md): x = shear axis, z up into the soil, y out of plane. Grains: a monolayer
with centres at y = 0, translation in y and rotation about x and z blocked. Wall group 0 (the rough
surface / the lower box half) travels −x at the shear velocity, so the soil moves +x relative to it
(shear_sign = +1); group 1 holds the fixed walls, group 2 the platen, a kinematic facet driven by a
velocity servo toward the target force. Walls are facets, one triangle per segment with an edge in
the grain plane y = 0 (no diagonal double contacts).

Periodic device (params `period` = L): YADE's cell is periodic in x, y and z, so it is L long and
tall and wide enough in y and z that nothing meets its own image there; the collider handles the
boundary (positions are never wrapped in the scene) and no body may span half the cell, so long
segments (a flat surface, the box's floor) are split into facets of at most L/4 (`split_facets`).
There is no fixed wall group (params list the platen second, as LIGGGHTS' mesh order), no exits and
no window (window_fx/fz = surface_fx/fz). The box test's bed (params `bed`: grain indices) is frozen
(blockedDOFs xyzXYZ) and moves −x with the floor during the shear; the surface force is the floor's
plus the bed grains'. Output x coordinates are wrapped into [0, L); io/yade.py unwraps contacts
across the boundary with recipe.json's period.

Protocol (engines/device.py): consolidation for n_consolidate steps, then chunks of n_chunk until
the platen force lies in its band (else 'NOT CONSOLIDATED', exit 4); then n_shear steps of shear with
history rows every n_history and snapshots every n_snapshot steps from the shear start. Grains whose
centres leave [x_lo, x_hi] × [z_lo, z_hi] are lost ('ERROR: Lost atoms', exit 3); grains past an exit
plane (interface) are erased and counted. Output in the case folder (read by io/yade.py):
history.csv, contacts.csv, particles.csv, bodies.json, shear_start.txt, rolling.json.

Cost (BENCHMARKS.md, issue 16): the PyRunner runs every step, so the per-step work is kept to the
servo (one C++ force sum, velocities set on State handles held from the start) and the rolling
update every ROLLING_PERIOD steps; the history rows read the surface's contacts from its facets
(not every grain's) and count contacts in C++. None of this changes what YADE computes: the run is
bit-identical to the first driver's (history, contacts, particles: four cases, walled and periodic).
"""

from __future__ import annotations

import json
import math
import os
import sys
import time

HISTORY_HEADER = "step,surface_fx,surface_fz,platen_fz,platen_z,n_contacts,window_fx,window_fz,n_grains,n_removed\n"
CONTACT_HEADER = "step,b1,b2,cx,cz,nx,nz,fx,fz,overlap,x1,z1,x2,z2\n"
PARTICLE_HEADER = "step,id,x,z,vx,vz,r\n"
ROLLING_PERIOD = 10          # steps between updates of the grain–facet rolling parameters


def servo_velocity(target: float, force: float, speed: float, band: float) -> float:
    """Platen velocity along z [m/s]: proportional to the relative force error (target − force)/target,
    reaching ±speed at ±band and capped there; a force below the target moves the platen down (−z).
    `force` is the grains' push on the platen (+z), `target` > 0 [N]."""
    err = (target - force) / target
    return -speed * max(-1.0, min(1.0, err / band))


def chunks_done(it: int, steps: dict) -> int | None:
    """Consolidation chunks completed at step `it` if it ends the first stretch (0) or a chunk,
    else None: the steps at which the platen force is checked against its band."""
    n_cons, n_chunk = steps["n_consolidate"], steps["n_chunk"]
    if it < n_cons or (it - n_cons) % n_chunk:
        return None
    return (it - n_cons) // n_chunk


def in_window(x: float, z: float, window) -> bool:
    """Whether a grain centre lies in the measuring window (x0, x1, z_top) [m]."""
    return window[0] < x < window[1] and z < window[2]


def wrap(x: float, period) -> float:
    """x brought into [0, period) (no period: x unchanged)."""
    return x - period * math.floor(x / period) if period else x


def split_facets(triangles, max_len: float) -> list[list[float]]:
    """In-plane facets (edge (x0, 0, z0)–(x1, 0, z1), apex at y = w over its midpoint) cut into
    equal pieces no longer than max_len, each with its apex over its own midpoint."""
    out = []
    for t in triangles:
        x0, z0, x1, z1, w = t[0], t[2], t[3], t[5], t[7]
        n = max(1, int(math.ceil(math.hypot(x1 - x0, z1 - z0) / max_len - 1e-9)))
        for k in range(n):
            a, b = k / n, (k + 1) / n
            xa, za, xb, zb = x0 + a * (x1 - x0), z0 + a * (z1 - z0), x0 + b * (x1 - x0), z0 + b * (z1 - z0)
            out.append([xa, 0.0, za, xb, 0.0, zb, 0.5 * (xa + xb), w, 0.5 * (za + zb)])
    return out


def in_bounds(x: float, z: float, bounds) -> bool:
    """Whether a grain centre lies inside the domain (x_lo, x_hi, z_lo, z_hi) [m]."""
    return bounds[0] < x < bounds[1] and bounds[2] < z < bounds[3]


def contact_row(it: int, id1: int, id2: int, point, normal, force, depth: float, p1, p2) -> str:
    """One contacts.csv row: 3-vectors are (x, y, z); only x and z are written."""
    return "%d,%d,%d,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n" % (
        it, id1, id2, point[0], point[2], normal[0], normal[2], force[0], force[2], depth, p1[0], p1[2], p2[0], p2[2])


def particle_row(it: int, i: int, pos, vel, radius: float) -> str:
    return "%d,%d,%.12g,%.12g,%.12g,%.12g,%.12g\n" % (it, i, pos[0], pos[2], vel[0], vel[2], radius)


def history_row(it: int, surface, platen_fz: float, platen_z: float, n_contacts: int, window, n_grains: int,
                n_removed: int) -> str:
    return "%d,%.12g,%.12g,%.12g,%.12g,%d,%.12g,%.12g,%d,%d\n" % (
        it, surface[0], surface[1], platen_fz, platen_z, n_contacts, window[0], window[1], n_grains, n_removed)


class Driver:
    """A case set up in YADE's scene (`y`: the yade module); `step` runs every time step."""

    def __init__(self, P: dict, y):
        self.y, self.O = y, y.O
        O, M = y.O, P["material"]
        self.P, self.M = P, M
        # materials: 0 grains, 1 moving group, 2 platen, 3 fixed side walls. Walls are stiffer (E_wall) because
        # YADE's facet–sphere geometry uses a facet radius of 2r (engines/yade.py)
        mats = [O.materials.append(y.FrictMat(young=E, poisson=M["nu"], density=M["density"],
                                              frictionAngle=math.atan(M[mu]), label=label))
                for E, mu, label in ((M["E"], "mu_pp", "grain"), (M["E_wall"], "mu_ps", "surface"),
                                     (M["E_wall"], "mu_pw", "wall"), (M["E_wall"], "mu_side", "side"))]
        G = P["grains"]
        self.period = P.get("period")
        if self.period:
            self.periodic_cell(G)
        bed = set(P.get("bed") or ())
        self.grain_ids, self.bed_ids = [], []
        for k, (x, z, r) in enumerate(zip(G["x"], G["z"], G["r"])):
            b = y.utils.sphere((x, 0.0, z), r, material=mats[0])
            b.state.blockedDOFs = "xyzXYZ" if k in bed else "yXZ"     # the bed: frozen, moved with the floor
            self.grain_ids.append(O.bodies.append(b))
            if k in bed:
                self.bed_ids.append(self.grain_ids[-1])
        self.n_grains = len(self.grain_ids)
        # wall groups in LIGGGHTS mesh order: index 0 = moving group ('ps'), then fixed walls, platen
        self.groups = []
        for g in P["walls"]:
            mat = mats[(1, 3, 2)[g["index"]]]        # wall groups: moving, fixed sides, platen
            tris = split_facets(g["triangles"], self.period / 4) if self.period else g["triangles"]
            self.groups.append([O.bodies.append(y.utils.facet([tuple(t[k:k + 3]) for k in (0, 3, 6)],
                                                              material=mat, fixed=True)) for t in tris])
        self.surface_ids, self.platen_ids = self.groups[0], self.groups[-1]
        self.loaded_ids = self.surface_ids + self.bed_ids          # what the soil loads below it
        # platen_z in the device's frame (the platen's reference point, params platen_z) whatever
        # point of its first facet YADE keeps as the body's position
        self.platen_dz = P["platen_z"] - O.bodies[self.platen_ids[0]].state.pos[2]
        self.surface_set = set(self.surface_ids)
        self.wall_ids = [i for ids in self.groups for i in ids]
        self.wall_set = set(self.wall_ids)
        # Python handles on the bodies' states (O.bodies[i].state looks the body up on every call, 3-4x
        # slower) and the grains' radii, as YADE holds them
        self.states = {i: O.bodies[i].state for i in self.grain_ids + self.wall_ids}
        self.radius = {i: O.bodies[i].shape.radius for i in self.grain_ids}
        self.platen_states = [self.states[i] for i in self.platen_ids]
        self.sum_forces = y.utils.sumForces            # C++ sum of a group's forces along an axis
        self.axes = (y.Vector3(1, 0, 0), y.Vector3(0, 0, 1))
        with open("bodies.json", "w") as fh:
            json.dump({"n_grains": self.n_grains, "first_grain": self.grain_ids[0],
                       "walls": [[min(ids), max(ids)] for ids in self.groups]}, fh)
        mm = y.MatchMaker
        O.engines = [
            y.ForceResetter(),
            y.InsertionSortCollider([y.Bo1_Sphere_Aabb(), y.Bo1_Facet_Aabb()]),
            y.InteractionLoop(
                [y.Ig2_Sphere_Sphere_ScGeom(), y.Ig2_Facet_Sphere_ScGeom()],
                [y.Ip2_FrictMat_FrictMat_MindlinPhys(
                    frictAngle=mm(matches=[(mats[0], mats[0], math.atan(M["mu_pp"])),
                                           (mats[0], mats[1], math.atan(M["mu_ps"])),
                                           (mats[0], mats[2], math.atan(M["mu_pw"])),
                                           (mats[0], mats[3], math.atan(M["mu_side"]))]),
                    betan=mm(algo="val", val=M["betan"]), betas=mm(algo="val", val=M["betas"]),
                    krot=M["krot"], eta=M["eta"])],
                [y.Law2_ScGeom_MindlinPhys_Mindlin(includeMoment=True)],
            ),
            y.PyRunner(command="interphase_step()", iterPeriod=1),
            y.NewtonIntegrator(gravity=(0, 0, -P["gravity"]), damping=0.0),
        ]
        O.dt = P["dt"]
        self.S = P["steps"]
        self.kr_wall, self.mu_r = M["krot_wall"], M["mu_r"]
        self.removed = 0
        self.start = None            # the step the shear starts at
        self.t_shear = self.c_shear = None
        self.hist = open("history.csv", "w")
        self.hist.write(HISTORY_HEADER)
        self.cont = open("contacts.csv", "w")
        self.cont.write(CONTACT_HEADER)
        self.part = open("particles.csv", "w")
        self.part.write(PARTICLE_HEADER)

    def periodic_cell(self, G) -> None:
        """x periodic over the period; y and z many times the device's extent, so nothing meets
        its own image there (YADE's cell is periodic in all three directions)."""
        b, d = self.P["bounds"], 2 * max(G["r"])
        self.O.periodic = True
        self.O.cell.setBox(self.period, 10 * max(d, self.P["wall_reach"]), 3 * (b[3] - b[2]))

    # ---- measurements
    def group_force(self, ids) -> tuple[float, float]:
        """(fx, fz) summed over the bodies `ids`, in their order (utils.sumForces: 0 + f·e per body,
        the same numbers as summing f[0], f[2] in Python, without a Python call per body)."""
        return self.sum_forces(ids, self.axes[0]), self.sum_forces(ids, self.axes[1])

    def window_force(self) -> tuple[float, float]:
        """Force ON the surface from the grains whose centres lie in the measuring window (None:
        the whole moving group). The facet is id1."""
        W = self.P["window"]
        if W is None or self.period:
            return self.group_force(self.loaded_ids)
        # the surface facets' contacts (a few per facet), not every grain's; summed in the order of
        # (grain id, facet id), the order of a loop over the grains and each grain's intrs(), which
        # YADE keeps sorted by the other body's id
        states, bodies, hits = self.states, self.O.bodies, []
        for s in self.surface_ids:
            for inter in bodies[s].intrs():
                if inter.isReal and inter.id1 == s:
                    p = states[inter.id2].pos
                    if in_window(p[0], p[2], W):
                        hits.append((inter.id2, s, inter.phys))
        hits.sort(key=lambda h: (h[0], h[1]))
        fx = fz = 0.0
        for _, _, ph in hits:
            f = ph.normalForce + ph.shearForce      # force on the grain
            fx -= f[0]
            fz -= f[2]
        return fx, fz

    def remove_escaped(self) -> None:
        """Erase grains whose centres passed an exit plane (x outside [0, L]): they left the box with
        the surface (LIGGGHTS: fix massflow/mesh … delete_atoms at the same planes)."""
        exits = self.P["exits"]
        if exits is None:
            return
        lo, hi, states = exits[0], exits[1], self.states
        for i in [i for i in self.grain_ids if not lo <= states[i].pos[0] <= hi]:
            self.O.bodies.erase(i)
            self.grain_ids.remove(i)
            del self.states[i]
            self.removed += 1

    def fail_if_lost(self, it: int) -> None:
        bounds = self.P["bounds"]
        if self.period:                  # x is periodic: only z can be left
            bounds = (-math.inf, math.inf, bounds[2], bounds[3])
        lost = sum(1 for i in self.grain_ids if not in_bounds(*self._xz(i), bounds))
        if lost:
            print("ERROR: Lost atoms: %d grains left the domain at step %d" % (lost, it))
            sys.stdout.flush()
            os._exit(3)              # sys.exit would only end the PyRunner call

    def _xz(self, i) -> tuple[float, float]:
        p = self.states[i].pos
        return p[0], p[2]

    def write_snapshot(self, it: int) -> None:
        states = self.states
        rows = []
        for inter in self.O.interactions:
            if not inter.isReal:
                continue
            g, ph = inter.geom, inter.phys
            rows.append(contact_row(it, inter.id1, inter.id2, self.at(g.contactPoint), g.normal,
                                    ph.normalForce + ph.shearForce,    # on body 2 (YADE: id1 → id2 normal)
                                    g.penetrationDepth, self.at(states[inter.id1].pos),
                                    self.at(states[inter.id2].pos)))
        self.cont.write("".join(rows))
        self.part.write("".join(particle_row(it, i, self.at(states[i].pos), states[i].vel, self.radius[i])
                                for i in self.grain_ids))

    def at(self, p) -> tuple[float, float, float]:
        """A point as written: x wrapped into [0, period) in the periodic device."""
        return wrap(p[0], self.period), p[1], p[2]

    # ---- grain–facet rolling: epsd2's wall values (the Ip2 functor's single krot/eta fit grain pairs)
    def grain_radius(self, inter) -> float:
        return self.radius[inter.id2 if inter.id1 in self.wall_set else inter.id1]

    def set_wall_rolling(self) -> None:
        """Rolling stiffness and cap of grain–facet contacts as LIGGGHTS epsd2 has them (kr = kt·r²,
        cap μr·r·Fn). Every ROLLING_PERIOD steps: a facet contact younger than that keeps the
        functor's (grain-pair) values until the next update."""
        kr, mu_r, radius, bodies = self.kr_wall, self.mu_r, self.radius, self.O.bodies
        for f in self.wall_ids:
            for inter in bodies[f].intrs():
                if inter.isReal:
                    ph = inter.phys
                    if ph.kr != kr:
                        ph.kr = kr
                        ph.maxBendPl = mu_r * radius[inter.id2 if inter.id1 == f else inter.id1]

    def set_velocity(self, ids, v) -> None:
        states = self.states
        for i in ids:
            states[i].vel = v

    # ---- the time step
    def step(self) -> None:
        P, S, O, y = self.P, self.S, self.O, self.y
        it = O.iter
        if self.kr_wall > 0 and it % ROLLING_PERIOD == 0:
            self.set_wall_rolling()
        fz_platen = self.sum_forces(self.platen_ids, self.axes[1])   # grains push the platen up: +z
        v = y.Vector3(0, 0, servo_velocity(P["platen_force"], fz_platen, P["servo_vmax"], P["servo_band"]))
        for s in self.platen_states:
            s.vel = v
        if self.start is None:
            done = chunks_done(it, S)
            if done is None:
                return
            self.fail_if_lost(it)
            if not P["platen_force_lo"] < fz_platen < P["platen_force_hi"]:
                if done < S["n_chunks_max"]:
                    return
                print("NOT CONSOLIDATED: platen force %.6g N, target %.6g–%.6g N, after %d chunks at step %d"
                      % (fz_platen, P["platen_force_lo"], P["platen_force_hi"], S["n_chunks_max"], it))
                sys.stdout.flush()
                os._exit(4)          # sys.exit would only end the PyRunner call
            self.start = it
            with open("shear_start.txt", "w") as fh:
                fh.write("%d\n" % it)
            self.set_velocity(self.loaded_ids, y.Vector3(-P["shear_velocity"], 0, 0))
            self.t_shear, self.c_shear = time.time(), time.process_time()
        s0 = self.start
        if (it - s0) % S["n_history"] == 0:
            surface = self.group_force(self.loaded_ids)
            pz = O.bodies[self.platen_ids[0]].state.pos[2] + self.platen_dz
            nc = O.interactions.countReal()
            self.remove_escaped()
            self.hist.write(history_row(it, surface, fz_platen, pz, nc, self.window_force(), len(self.grain_ids),
                                        self.removed))
        if (it - s0) % S["n_snapshot"] == 0:
            self.write_snapshot(it)
            self.fail_if_lost(it)
        if it - s0 >= S["n_shear"]:
            O.pause()                # the last shear step: the run ends after it

    def finish(self, t0: float, c0: float = 0.0) -> None:
        """Close the output, record the rolling parameters in force and the stage wall times."""
        for fh in (self.hist, self.cont, self.part):
            fh.close()
        # a check that set_wall_rolling reached the facet contacts (those younger than its period may
        # still hold the functor's values)
        facet = [inter for f in self.wall_ids for inter in self.O.bodies[f].intrs() if inter.isReal]
        with open("rolling.json", "w") as fh:
            json.dump({"facet_contacts": len(facet), "kr_wall": self.kr_wall,
                       "matched": sum(1 for inter in facet if inter.phys.kr == self.kr_wall
                                      and abs(inter.phys.maxBendPl - self.mu_r * self.grain_radius(inter))
                                      <= 1e-12 * self.grain_radius(inter))}, fh)
        end, cend = time.time(), time.process_time()
        # wall times of the two stages, for bench/bench_yade.py (particle-steps per second), and this
        # process's CPU times (steadier than wall times on a shared machine)
        print("interphase: consolidation %d steps %.3f s; shear %d steps %.3f s; grains %d; cpu %.3f s, %.3f s" % (
            self.start, self.t_shear - t0, self.S["n_shear"] + 1, end - self.t_shear, self.n_grains,
            self.c_shear - c0, cend - self.c_shear))
        print("interphase: finished %d steps" % self.O.iter)
        sys.stdout.flush()


def main(params_path: str = "params.json") -> None:
    """Run the case of `params_path` in the current YADE scene, writing output into the cwd."""
    import __main__

    import yade

    with open(params_path) as fh:
        P = json.load(fh)
    driver = Driver(P, yade)
    __main__.interphase_step = driver.step      # PyRunner commands run in __main__'s namespace
    t0, c0 = time.time(), time.process_time()
    S = P["steps"]
    yade.O.run(S["n_consolidate"] + S["n_chunks_max"] * S["n_chunk"] + S["n_shear"] + 1, True)
    driver.finish(t0, c0)
