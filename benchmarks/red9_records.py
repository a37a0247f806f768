"""Red team 9's records: python -m benchmarks.red9_records OUTDIR [--only R01,R02]  -- writes CSV, setup TOML,
truth JSON and the noise-free output (_clean.npz) of each (kept as the helper wrote them)."""
import sys, os, json, math, time
import numpy as np
from benchmarks.red9_plant import Plant

GAINS = dict(k_p=2.0, k_I=5.0, k_D=0.01)

def nuis(rng):
    f = lambda: 1 + rng.choice([-1, 1]) * rng.uniform(0.02, 0.05)
    return dict(m_v=580e3 * f(), mu_c=0.4 * f(), mu_s=0.51 * f(), J_v=1.678e6 * f())

# name: (plant kwargs beyond base, effects-off kwargs per effect, fs, T, law_in_setup, expected, setup extras, note)
def specs():
    S = {}
    S['R01'] = dict(eff={}, base=dict(m_v=580e3 * 1.20, J_v=1.678e6 * 0.97, mu_c=0.4 * 1.03, mu_s=0.51 * 0.98),
                    fs=50, T=40, law='paper', expected=['nothing'],
                    form='no effect; burden mass +20 % off the setup (fill unknown), J_v -3 %, mu_c +3 %, mu_s -2 %')
    S['R02'] = dict(eff={'viscous_drag': dict(B_o=6e5)}, fs=25, T=40, law='paper', expected=['viscous_drag'],
                    form='viscous drag B_o 6e5 N m s/rad at the kiln (0.3x the usual bottom); 25 Hz')
    S['R03'] = dict(eff={'drivetrain_compliance': dict(k_po=1.0e8, C_po=3e5)}, fs=100, T=40, law='paper',
                    expected=['drivetrain_compliance'],
                    form='compliance k_po 1e8 N m/rad, C_po 3e5 (very light damping, 0.15x the usual bottom); 100 Hz')
    S['R04'] = dict(eff={'motor_coulomb_friction': dict(T_cm=300.0)}, fs=50, T=60, law='paper',
                    expected=['motor_coulomb_friction'], form='motor Coulomb friction 300 N m (3x usual top), tanh over 0.005 rad/s; 60 s')
    S['R05'] = dict(eff={'speed_sensor_lag': dict(tau_ctrl=0.008)}, fs=100, T=40,
                    law='paper', expected=['speed_sensor_lag'],
                    form='first-order 8 ms filter (15 ms and a PI with k_D = 0 made this loop unstable) in the speed feedback of the controller only, logged speed unfiltered; 100 Hz')
    S['R06'] = dict(eff={'current_limit': dict(I_max='0.99peak')}, ramp=120.0, fs=50, T=40, law='paper', expected=['current_limit'],
                    form='ideal current clamp (integrator frozen) at 0.99 of the unlimited peak, fast ramp 120 rpm/s, paper law: the limit is met after the ramp, at the held burden and at the tops of the sliding oscillation (the ramp needs only ~230 A; the paper-law steady mean is 98.7 % of the peak, a limit at 0.975 stalls the kiln); speed dips up to 10 rpm')
    S['R07'] = dict(eff={'drivetrain_compliance': dict(k_po=5e7, C_po=2e6), 'viscous_drag': dict(B_o=1e7)}, fs=50, T=40,
                    law='torque', expected=['torque_friction_law', 'drivetrain_compliance', 'viscous_drag'],
                    form='torque law (stated) + compliance at the bottom edges (k_po 5e7, C_po 2e6) + viscous drag at the top edge (B_o 1e7)')
    S['R08'] = dict(eff={'armature_reaction (outside)': dict(ar_a=0.05)}, fs=50, T=40, law='torque',
                    expected=['torque_friction_law', 'unexplained or nothing more'],
                    form='torque law (stated) + armature reaction: flux factor 1 - 0.05 (i/1000 A)^2 (0.10 ran away to 3.5 kA) on k_i and k_b (outside the catalogue)')
    S['R09'] = dict(eff={'tooth_pass_ripple (outside)': dict(T_tp=1.2e5, z_tp=240, phi_tp=0.7)}, fs=100, T=40, law='paper',
                    expected=['nothing or unexplained'],
                    form='girth-gear tooth-pass torque ripple 1.2e5 N m at the kiln, 240 per kiln revolution (1.86 Hz at 500 rpm) (outside); 100 Hz')
    S['R10'] = dict(eff={'second_motor': dict(J_m2=6.0)}, scurve=1.5, fs=50, T=60, law='paper', expected=['second_motor'],
                    form='S-curve reference (rounding 1.5 s, 74 rpm/s) logged + second motor J_m2 6 kg m^2 (0.6x usual bottom); 60 s')
    return S

def ar1(rng, n, sig, tau, fs):
    a = math.exp(-1.0 / (tau * fs))
    e = rng.normal(0, sig * math.sqrt(1 - a * a), n)
    x = np.zeros(n); x[0] = rng.normal(0, sig)
    for k in range(1, n):
        x[k] = a * x[k - 1] + e[k]
    return x

def main(argv=None):
    argv = sys.argv if argv is None else argv
    if len(argv) < 2 or argv[1].startswith('-'):
        sys.exit('usage: python -m benchmarks.red9_records OUTDIR [--only R01,R08]: writes the records\' CSV, '
                 'TOML and truth into OUTDIR (made if missing)')
    outdir = argv[1]
    only = None
    if '--only' in argv:
        only = argv[argv.index('--only') + 1].split(',')
    os.makedirs(outdir, exist_ok=True)
    S = specs()
    for idx, (name, s) in enumerate(S.items()):
        if only and name not in only:
            continue
        t_start = time.time()
        rng = np.random.default_rng(900 + idx)
        base = nuis(rng)
        base.update(s.get('base', {}))
        gains = s.get('gains', GAINS)
        common = dict(base, law=s['law'], **gains)
        if 'ramp' in s:
            common['ramp_rate'] = s['ramp']
        if 'scurve' in s:
            common['scurve_Tj'] = s['scurve']
        effkw = {}
        for e, kw in s['eff'].items():
            effkw.update(kw)
        vis = {}
        if effkw.get('I_max') == '0.99peak':
            o0, _ = Plant(**common).run(s['T'], s['fs'])
            peak = o0[:, 1].max()
            effkw['I_max'] = 0.99 * peak
            vis['unlimited_peak_A'] = peak
        out, ev = Plant(**common, **effkw).run(s['T'], s['fs'])
        t0 = 1.0
        m = out[:, 0] >= t0
        if s['eff']:
            o_off, _ = Plant(**common).run(s['T'], s['fs'])
            d = out[m, 1] - o_off[m, 1]
            vis['all'] = dict(rms=float(np.sqrt(np.mean(d ** 2))), max=float(np.abs(d).max()))
            if len(s['eff']) > 1:
                for e, kw in s['eff'].items():
                    kw = {k: effkw[k] for k in kw}
                    o1, _ = Plant(**common, **kw).run(s['T'], s['fs'])
                    d = o1[m, 1] - o_off[m, 1]
                    vis[e + ' alone'] = dict(rms=float(np.sqrt(np.mean(d ** 2))), max=float(np.abs(d).max()))
        N = len(out)
        fs = s['fs']
        sI = (rng.uniform(2.0, 3.0), rng.uniform(1.5, 3.0), rng.uniform(0.3, 0.5))
        sW = (rng.uniform(0.15, 0.25), rng.uniform(0.1, 0.2), rng.uniform(0.2, 0.3))
        I = out[:, 1] + rng.normal(0, sI[0], N) + ar1(rng, N, sI[1], sI[2], fs)
        W = out[:, 2] + rng.normal(0, sW[0], N) + ar1(rng, N, sW[1], sW[2], fs)
        np.savez(os.path.join(outdir, name + '_clean.npz'), out=out)
        with open(os.path.join(outdir, name + '.csv'), 'w') as f:
            f.write('# red team 9 record %s, logger at %g Hz\n' % (name, fs))
            f.write('time_s,current_A,speed_rpm,speed_ref_rpm\n')
            for k in range(N):
                f.write('%.3f,%.2f,%.3f,%.3f\n' % (out[k, 0], I[k], W[k], out[k, 3]))
        tom = ['[controller]', 'gains = "given"'] + ['%s = %r' % (k, v) for k, v in gains.items()]
        tom += ['', '[drive]', 'ramp_rate = %r' % common.get('ramp_rate', 74.0), 'omega_ref = 500.0']
        if s['law'] == 'torque':
            tom += ['', '[kiln]', 'friction_law = "torque"']
        open(os.path.join(outdir, name + '.toml'), 'w').write('\n'.join(tom) + '\n')
        truth = dict(record=name, form=s['form'], expected=s['expected'], law=s['law'], fs=fs, T=s['T'],
                     plant_base=base, gains=gains, effect_values={k: v for k, v in effkw.items()},
                     ramp_rate=common.get('ramp_rate', 74.0), scurve_Tj=s.get('scurve'),
                     visibility_current_A=vis, noise=dict(current_white_A=sI[0], current_ar1_A=sI[1], current_ar1_tau_s=sI[2],
                                                          speed_white_rpm=sW[0], speed_ar1_rpm=sW[1], speed_ar1_tau_s=sW[2]),
                     n_events=len(ev), peak_current_A=float(out[:, 1].max()), final_current_A=float(out[-1, 1]))
        json.dump(truth, open(os.path.join(outdir, name + '_truth.json'), 'w'), indent=1)
        print(name, 'events', len(ev), 'vis', {k: (round(v['rms'], 1), round(v['max'], 1)) if isinstance(v, dict) else round(v, 1) for k, v in vis.items()},
              'peak %.0f end %.0f' % (out[:, 1].max(), out[-1, 1]), '%.0fs' % (time.time() - t_start), flush=True)

if __name__ == '__main__':
    main()
