# A plain YADE script of a generated case's physics, for bench/bench_yade.py: what one would write
# by hand for the same run, with no output. Same grains, facets, materials and engines as
# engines/yade_driver.py builds from the case's params.json (Hertz–Mindlin with rolling resistance,
# the grain–facet rolling values set every 10 steps, the platen servo every step, the consolidation
# checks at chunk ends, the shear, grains past the exits erased every n_history steps); no history,
# no contacts, no particles, no checks for lost grains.
#
# Run in a rendered YADE case folder: yade -n -x bench/yade_plain.py params.json [check]
# It prints the driver's stage line ("interphase: consolidation ... shear ... cpu ..."). With `check`
# it writes particles_plain.csv at the snapshot steps, in particles.csv's format: identical files
# show that this script and the generated driver run the same physics.
import json
import math
import sys
import time

P = json.load(open(sys.argv[1]))
CHECK = len(sys.argv) > 2 and sys.argv[2] == "check"
M, G, S = P["material"], P["grains"], P["steps"]
period = P.get("period")
if period:      # x periodic; y and z far larger than the device (as the driver)
    b = P["bounds"]
    O.periodic = True
    O.cell.setBox(period, 10 * max(2 * max(G["r"]), P["wall_reach"]), 3 * (b[3] - b[2]))
mats = [O.materials.append(FrictMat(young=E, poisson=M["nu"], density=M["density"], frictionAngle=math.atan(M[mu])))
        for E, mu in ((M["E"], "mu_pp"), (M["E_wall"], "mu_ps"), (M["E_wall"], "mu_pw"), (M["E_wall"], "mu_side"))]
bed = set(P.get("bed") or ())
grains = []
for k, (x, z, r) in enumerate(zip(G["x"], G["z"], G["r"])):
    b = sphere((x, 0.0, z), r, material=mats[0])
    b.state.blockedDOFs = "xyzXYZ" if k in bed else "yXZ"
    grains.append(O.bodies.append(b))


def split(tris, n_max):      # no body may span half the periodic cell (the driver's split_facets)
    out = []
    for t in tris:
        x0, z0, x1, z1, w = t[0], t[2], t[3], t[5], t[7]
        n = max(1, int(math.ceil(math.hypot(x1 - x0, z1 - z0) / n_max - 1e-9)))
        for k in range(n):
            a, c = k / n, (k + 1) / n
            xa, za, xb, zb = x0 + a * (x1 - x0), z0 + a * (z1 - z0), x0 + c * (x1 - x0), z0 + c * (z1 - z0)
            out.append([xa, 0.0, za, xb, 0.0, zb, 0.5 * (xa + xb), w, 0.5 * (za + zb)])
    return out


groups = [[O.bodies.append(facet([tuple(t[k:k + 3]) for k in (0, 3, 6)], material=mats[(1, 3, 2)[g["index"]]], fixed=True))
           for t in (split(g["triangles"], period / 4) if period else g["triangles"])] for g in P["walls"]]
walls = [i for g in groups for i in g]
loaded = groups[0] + [grains[k] for k in sorted(bed)]
platen = [O.bodies[i].state for i in groups[-1]]
radius = {i: O.bodies[i].shape.radius for i in grains}
mm = MatchMaker
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Facet_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Facet_Sphere_ScGeom()],
                    [Ip2_FrictMat_FrictMat_MindlinPhys(
                        frictAngle=mm(matches=[(mats[0], mats[0], math.atan(M["mu_pp"])), (mats[0], mats[1], math.atan(M["mu_ps"])),
                                               (mats[0], mats[2], math.atan(M["mu_pw"])), (mats[0], mats[3], math.atan(M["mu_side"]))]),
                        betan=mm(algo="val", val=M["betan"]), betas=mm(algo="val", val=M["betas"]), krot=M["krot"], eta=M["eta"])],
                    [Law2_ScGeom_MindlinPhys_Mindlin(includeMoment=True)]),
    PyRunner(command="step()", iterPeriod=1),
    NewtonIntegrator(gravity=(0, 0, -P["gravity"]), damping=0.0),
]
O.dt = P["dt"]
kr, mu_r = M["krot_wall"], M["mu_r"]
target, vmax, band = P["platen_force"], P["servo_vmax"], P["servo_band"]
lo, hi = P["platen_force_lo"], P["platen_force_hi"]
n_cons, n_chunk, n_hist, n_snap, n_shear = S["n_consolidate"], S["n_chunk"], S["n_history"], S["n_snapshot"], S["n_shear"]
exits = P["exits"]
ez = Vector3(0, 0, 1)
states = {i: O.bodies[i].state for i in grains}
start = None
out = open("particles_plain.csv", "w") if CHECK else None
T = {}


def step():
    global start
    it = O.iter
    if kr > 0 and it % 10 == 0:           # grain–facet contacts: LIGGGHTS epsd2's wall rolling values
        for f in walls:
            for i in O.bodies[f].intrs():
                if i.isReal:
                    ph = i.phys
                    if ph.kr != kr:
                        ph.kr = kr
                        ph.maxBendPl = mu_r * radius[i.id2 if i.id1 == f else i.id1]
    fz = utils.sumForces(groups[-1], ez)
    v = Vector3(0, 0, -vmax * max(-1.0, min(1.0, (target - fz) / target / band)))
    for s in platen:
        s.vel = v
    if start is None:
        if it < n_cons or (it - n_cons) % n_chunk or not lo < fz < hi:
            return
        start = it
        for i in loaded:
            O.bodies[i].state.vel = Vector3(-P["shear_velocity"], 0, 0)
        T["t"], T["c"] = time.time(), time.process_time()
    k = it - start
    if exits is not None and k % n_hist == 0:
        for i in [i for i in grains if not exits[0] <= states[i].pos[0] <= exits[1]]:
            O.bodies.erase(i)
            grains.remove(i)
    if CHECK and k % n_snap == 0:
        out.write("".join("%d,%d,%.12g,%.12g,%.12g,%.12g,%.12g\n" % (
            it, i, states[i].pos[0] - period * math.floor(states[i].pos[0] / period) if period else states[i].pos[0],
            states[i].pos[2], states[i].vel[0], states[i].vel[2], radius[i]) for i in grains))
    if k >= n_shear:
        O.pause()


t0, c0 = time.time(), time.process_time()
O.run(n_cons + S["n_chunks_max"] * n_chunk + n_shear + 1, True)
t1, c1 = time.time(), time.process_time()
if out:
    out.close()
print("interphase: consolidation %d steps %.3f s; shear %d steps %.3f s; grains %d; cpu %.3f s, %.3f s" % (
    start, T["t"] - t0, n_shear + 1, t1 - T["t"], len(G["x"]), T["c"] - c0, c1 - T["c"]))
print("interphase: finished %d steps" % O.iter)
