"""YADE side of the grain-shape cell (studies/shape_and_kinematics/shape_cell.py writes its input and reads its output): a
periodic drained triaxial compression of spheres or rigid clumps, run by the same protocol as the
tool's LIGGGHTS cell (engines/cell.py, recipe.CellRecipe) so that spheres here and there can be
compared before clumps are read.

    yade -n -x studies/shape_and_kinematics/yade_shape_cell.py IN.json

IN.json (SI units): grains [[[x, y, z, r], ...] per grain: one member = a sphere, more = a clump],
solid (Σ grain volume, overlaps of a clump's members counted once), L (the start cube), contact (the
tool's engines.yade.contact_parameters), mu, mu_r, prep, s3, rate, eps_end, dt, gain, every, window,
compaction_cap, shear_cap, n_consolidate, n_chunk, n_chunks_max, tolerance, settle_energy, n_settle,
n_history, out, kinematics ("yade", or "remap": the grains moved with the box as LIGGGHTS' `remap x` does),
check_stress (compare stress() with the sum written out, at the end of consolidation).

The stress: YADE's utils.getStress, the Love–Weber sum Σ f ⊗ branch / V, whose branch for a clump
member runs from its clump's centroid (checked at the end of every consolidation against the sum
written out here, slow_stress). PeriTriaxController is not used: it sums f ⊗ n (r1 + r2), the branch
between the touching spheres' centres, which misses what holds a clump together (docs/engines.md).
Compression positive.

Servo (the LIGGGHTS cell's): each free axis' strain rate = gain·(σ − σ3′)/σ3′ capped at ±cap, σ the
mean over the last `window` evaluations, one evaluation every `every` steps; the axial axis is driven
at `rate` (engineering, on the length at the start of the compression). Writes OUT (JSON) last.
"""
import json
import math
import sys
import time

from yade import utils

cfg = json.load(open(sys.argv[-1]))
C = cfg['contact']
t_wall = time.time()
O.periodic = True
L = cfg['L']
O.cell.hSize = Matrix3(L, 0, 0, 0, L, 0, 0, 0, L)
prep = cfg['prep']
mat = O.materials.append(FrictMat(young=C['E'], poisson=C['nu'], frictionAngle=math.atan(prep * cfg['mu']),
                                  density=C['density']))
clumps = False
for g in cfg['grains']:
    spheres = [sphere(Vector3(x, y, z), r, material=mat) for x, y, z, r in g]
    if len(spheres) == 1:
        O.bodies.append(spheres[0])
    else:
        O.bodies.appendClumped(spheres)
        clumps = True
if clumps:
    # a clump's mass and inertia from its members' union (appendClumped sums the members, so an
    # overlap would count twice)
    O.bodies.updateClumpProperties(discretization=15)


def rolling(eta):
    # YADE caps the rolling moment only when eta > 0: eta 0 with krot > 0 would be an unlimited spring
    return (C['krot'] if eta > 0 else 0.0), eta


krot0, eta0 = rolling(prep * cfg['mu_r'] / 2)
ip2 = Ip2_FrictMat_FrictMat_MindlinPhys(betan=C['betan'], betas=C['betas'], krot=krot0, eta=eta0)
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb()], allowBiggerThanPeriod=False),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [ip2], [Law2_ScGeom_MindlinPhys_Mindlin(includeMoment=True)]),
    NewtonIntegrator(damping=0.0),
    PyRunner(iterPeriod=cfg['every'], command='servo()'),
]
O.dt = cfg['dt']
# 'remap' emulates LIGGGHTS' fix deform … remap x: the cell moves, the grains' positions are mapped
# affinely with it at each servo evaluation, and their velocities never carry the affine field (YADE's
# default, homoDeform 2, puts ∇v·x into every velocity, so contacts see the affine relative motion)
REMAP = cfg.get('kinematics', 'yade') == 'remap'
if REMAP:
    O.cell.homoDeform = 0
    st_h = [Matrix3(O.cell.hSize)]
s3 = cfg['s3']
solid = cfg['solid']


def stress():
    """Diagonal (σxx, σyy, σzz) of the contact stress with centroid branches, compression positive [Pa].
    utils.getStress takes a clump member's branch from its clump's centroid (measured: it equals
    slow_stress below, and the member-centre sum reads 12 % lower on dimers at 200 kPa)."""
    S = -utils.getStress()             # YADE: tension positive
    return [S[0, 0], S[1, 1], S[2, 2]]


def slow_stress(members_only=False):
    """The same diagonal by the definition, interaction by interaction (a check of stress())."""
    def centre(i):
        b = O.bodies[i]
        return O.bodies[b.clumpId].state.pos if b.isClumpMember and not members_only else b.state.pos
    S = [0.0, 0.0, 0.0]
    h = O.cell.hSize
    for I in O.interactions:
        if I.isReal:
            f = I.phys.normalForce + I.phys.shearForce          # on id2
            br = centre(I.id2) - centre(I.id1) + h * Vector3(*I.cellDist)
            for k in range(3):
                S[k] += f[k] * br[k] / O.cell.volume
    return S


st = {'phase': 'cons', 'recent': [], 'hist': [], 'start': 0, 'chunks': 0, 'dep': 0.0, 'gain': cfg['gain']}


def ke_per_grain():
    return utils.kineticEnergy() / len(cfg['grains'])


def restore_friction():
    mu, eta = cfg['mu'], cfg['mu_r'] / 2
    kr, eta = rolling(eta)
    O.materials[0].frictionAngle = math.atan(mu)
    ip2.krot, ip2.eta = kr, eta
    for I in O.interactions:
        if I.isReal:
            I.phys.tangensOfFrictionAngle = mu
            I.phys.kr = kr
            I.phys.maxBendPl = eta * 0.5 * (I.geom.refR1 + I.geom.refR2)


def remap():
    F = O.cell.hSize * st_h[0].inverse()
    for b in O.bodies:
        if not b.isClumpMember:
            b.state.pos = F * b.state.pos
    st_h[0] = Matrix3(O.cell.hSize)


def servo():
    if REMAP:
        remap()
    sig = stress()
    rec = st['recent']
    rec.append(sig)
    del rec[:-cfg['window']]
    s = [sum(r[k] for r in rec) / len(rec) for k in range(3)]
    shear = st['phase'] == 'shear'
    cap = cfg['shear_cap'] if shear else cfg['compaction_cap']
    vg = Matrix3.Zero
    for k in range(2 if shear else 3):
        vg[k, k] = max(-cap, min(cap, st['gain'] * (s[k] - s3) / s3))
    if shear:
        vg[2, 2] = -cfg['rate'] * st['z0'] / O.cell.hSize[2, 2]
    O.cell.velGrad = vg
    n = O.iter - st['start']
    if st['phase'] == 'cons':
        if n >= cfg['n_consolidate'] + st['chunks'] * cfg['n_chunk']:
            at_rest = ke_per_grain() < cfg['settle_energy'] * s3 * cfg['d50'] ** 3
            if all(abs(x - s3) < cfg['tolerance'] * s3 for x in s) and at_rest:
                if cfg.get('check_stress'):
                    st['stress_check'] = [stress(), slow_stress(), slow_stress(True)]
                restore_friction()
                st['phase'], st['start'] = 'settle', O.iter
                print('consolidated at iter %d, wall %.0f s' % (O.iter, time.time() - t_wall), flush=True)
            else:
                st['chunks'] += 1
                if st['chunks'] > cfg['n_chunks_max']:
                    st['error'] = 'consolidation did not settle: stresses %s' % s
                    O.pause()
    elif st['phase'] == 'settle':
        if n >= cfg['n_settle']:
            st['phase'], st['start'] = 'shear', O.iter
            st['z0'], st['v0'] = O.cell.hSize[2, 2], O.cell.volume
            st['e0'] = O.cell.volume / solid - 1
            st['hist'].append((0.0, 0.0, s[2] / (0.5 * (s[0] + s[1])), st['e0']))
    else:
        st['dep'] = max(st['dep'], abs(s[0] - s3) / s3, abs(s[1] - s3) / s3)
        e1 = 1 - O.cell.hSize[2, 2] / st['z0']
        if n % cfg['n_history'] == 0 or e1 >= cfg['eps_end']:
            e = O.cell.volume / solid - 1
            st['hist'].append((e1, 1 - O.cell.volume / st['v0'], s[2] / (0.5 * (s[0] + s[1])), e))
            if len(st['hist']) % 40 == 0:
                print('eps1 %.3f  iter %d  wall %.0f s' % (e1, O.iter, time.time() - t_wall), flush=True)
        if e1 >= cfg['eps_end']:
            O.pause()


O.run()
O.wait()
with open(cfg['out'] + '.part', 'w') as fh:
    json.dump({'hist': st['hist'], 'e0': st.get('e0'), 'error': st.get('error'),
               'stress_check': st.get('stress_check'), 'sigma3_departure_max': st['dep'], 'iters': O.iter,
               'wall': time.time() - t_wall, 'n_grains': len(cfg['grains']), 'n_spheres': len(O.bodies) - len(
                   [b for b in O.bodies if b.isClump])}, fh)
import os  # noqa: E402
os.replace(cfg['out'] + '.part', cfg['out'])     # the result appears whole, last
