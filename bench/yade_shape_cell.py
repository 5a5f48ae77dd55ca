"""A first YADE periodic triaxial cell for grain shape: spheres against dimer clumps under one contact law
(Hertz–Mindlin, no rolling resistance), the stress from branches between clump centroids (the member
virial misses what holds a clump together: docs/engines.md). A prototype outside the tool, kept so the
shape lever can be built from it; NOT a source of numbers yet:
- the lateral servo is proportional only, so σ3′ runs 35–90 % above its target during the compression
  (measured: 272–380 kPa for 200 kPa); it needs integral action (or the LIGGGHTS cell's stiffness-scaled
  gain) before a run means anything;
- 300 grains (a cell ~6 D50 a side), one seed, the stress loop in Python every 50 steps (YADE's own is
  the slow part here: ~1 ms a step for 600 spheres on this machine).

    yade -n -x bench/yade_shape_cell.py shape=sphere|dimer n=300 eps=0.3 seed=1 out=hist.json

Writes [ε1, εv, σ1′/σ3′, e] every 50 steps of the compression (read with bench/state_line.state_row).
"""
import json
import math
import random
import sys
import time
args = dict(a.split('=') for a in sys.argv[1:])
shape = args.get('shape', 'sphere')          # sphere | dimer
seed = int(args.get('seed', 1)); n = int(args.get('n', 500)); ar = float(args.get('ar', 1.5))
mu = float(args.get('mu', 0.53)); s3 = float(args.get('s3', 200e3)); rate = float(args.get('rate', 20.0))
eps_end = float(args.get('eps', 0.4)); out = args.get('out', 'hist.json')
G, nu, rho, d50 = 50e6, 0.3, 2650.0, 0.14e-3
E = 2 * G * (1 + nu)
random.seed(seed)
O.periodic = True
mat = O.materials.append(FrictMat(young=E, poisson=nu, frictionAngle=0.0, density=rho))
# grains: sphere diameter d (sphere) or two spheres of diameter a, centres (ar-1)·a apart (dimer, length ar·a),
# with a chosen so that the clump's volume equals the sphere's: volume-equivalent diameter d50 for both
def dimer_a(d):
    s = ar - 1.0                                  # centre distance in units of a
    # union volume of two spheres radius a/2 at distance s·a (s<1): 2V - lens
    r = 0.5; h = r - s / 2                        # cap height
    v = 2 * (4 / 3 * math.pi * r ** 3) - 2 * (math.pi * h * h * (3 * r - h) / 3)
    return d * ((math.pi / 6) / v) ** (1 / 3), v
L = (n * math.pi / 6 * d50 ** 3 / 0.25) ** (1 / 3) * 1.0
O.cell.hSize = Matrix3(L, 0, 0, 0, L, 0, 0, 0, L)
sizes = [d50 * f for f in (0.8, 0.9, 1.0, 1.1, 1.2)]
for i in range(n):
    d = random.choice(sizes)
    c = Vector3(random.random() * L, random.random() * L, random.random() * L)
    if shape == 'sphere':
        O.bodies.append(sphere(c, d / 2, material=mat))
    else:
        a, _ = dimer_a(d)
        ax = Vector3(random.gauss(0, 1), random.gauss(0, 1), random.gauss(0, 1)).normalized()
        off = ax * (ar - 1.0) * a / 2
        O.bodies.appendClumped([sphere(c - off, a / 2, material=mat), sphere(c + off, a / 2, material=mat)])
def solid_volume():
    v = 0.0
    for b in O.bodies:
        # a clump's mass is its members' sum (YADE's default): at ar 1.5 the overlap counts twice, so the
        # solid volume reads 18.5 % high and a dimer packing's e low (to fix with updateClumpProperties)
        if not b.isClumpMember:
            v += b.state.mass / rho
    return v
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()], allowBiggerThanPeriod=False),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_MindlinPhys()],
                             [Law2_ScGeom_MindlinPhys_Mindlin()]),
             NewtonIntegrator(damping=0.2), PyRunner(iterPeriod=50, command='servo()', label='pr')]
O.dt = 0.3 * PWaveTimeStep()
def centre(i):
    b = O.bodies[i]
    return O.bodies[b.clumpId].state.pos if b.isClumpMember else b.state.pos
def stress():
    s = Matrix3.Zero
    h = O.cell.hSize
    for I in O.interactions:
        if not I.isReal: continue
        f = I.phys.normalForce + I.phys.shearForce        # on id2 (YADE: applied to id1 with minus)
        br = centre(I.id2) - centre(I.id1) + h * Vector3(I.cellDist[0], I.cellDist[1], I.cellDist[2])
        s += f.outer(br)
    return s / O.cell.volume                                # compression positive (checked: positive under load)
t0 = time.time()
state = {'phase': 'cons', 'hist': [], 'z0': None, 'v0': None}
GAIN, CAP = 20.0, 50.0
GAIN_C, CAP_C = 20.0, 50.0
def servo():
    S = stress(); sig = [S[0, 0], S[1, 1], S[2, 2]]
    vg = Matrix3.Zero
    for k in range(3):
        if state['phase'] == 'shear' and k == 2:
            vg[2, 2] = -rate * O.cell.hSize[2, 2] / state['z0']  # engineering rate on the initial length
            continue
        g, c = (GAIN, CAP) if state['phase'] == 'shear' else (GAIN_C, CAP_C)
        vg[k, k] = max(-c, min(c, g * (sig[k] - s3) / s3))
    O.cell.velGrad = vg
    if O.iter % 50000 == 0:
        print(O.iter, state['phase'], [round(x / 1e3, 1) for x in sig], round(unbalancedForce(), 3), round(time.time() - t0, 1), flush=True)
    if state['phase'] == 'cons':
        if all(abs(x - s3) < 0.01 * s3 for x in sig) and unbalancedForce() < 0.01:
            state['phase'] = 'settle'; state['t'] = O.iter
            O.materials[0].frictionAngle = math.atan(mu)
            for I in O.interactions:
                if I.isReal: I.phys.tangensOfFrictionAngle = mu
    elif state['phase'] == 'settle':
        if O.iter - state['t'] > 4000 and all(abs(x - s3) < 0.01 * s3 for x in sig):
            state['phase'] = 'shear'; state['z0'] = O.cell.hSize[2, 2]; state['v0'] = O.cell.volume
            print('consolidated at', O.iter, 'e0', O.cell.volume / solid_volume() - 1, flush=True)
    else:
        e1 = 1 - O.cell.hSize[2, 2] / state['z0']; ev = 1 - O.cell.volume / state['v0']
        s3m = (sig[0] + sig[1]) / 2
        state['hist'].append((e1, ev, sig[2] / s3m, O.cell.volume / solid_volume() - 1))
        if e1 >= eps_end:
            json.dump(state['hist'], open(out, 'w')); O.pause()
t = t0 = time.time()
O.run(); O.wait()
print('done', shape, seed, 'iters', O.iter, 'wall', round(time.time() - t), flush=True)
