#!/usr/bin/env python3
"""illum against Mitsuba 3 at equal render time (docs/performance-sampling.md, "Against Mitsuba 3
at equal time"). For measurement only: needs the mitsuba package (a venv outside the repo) and a
release build of illum.

For each scene (an illum scene that scripts/to-mitsuba.py converts, e.g. scenes/bench/mitsuba-*.json):
1. a reference: Mitsuba for --ref-time seconds (cached in --out);
2. --rounds rounds, interleaved: Mitsuba for --time seconds, then illum with each option set
   (`illum render --time T`). relMSE (epsilon 0.01, as src/metrics.rs) against the reference.

Equal time: illum's render time is what it prints as "render X s" (its kernel compilation is
excluded). Mitsuba renders a sample count calibrated from its previous render of that scene to
take T seconds; its first (warm-up) render, which includes its JIT compilation, is timed apart and
not counted. Some samplers (multijitter, ldsampler) compile Mitsuba's kernels again for every
sample count, so each timed render follows an untimed one of the same count. Each relMSE is scaled by (seconds taken / T), i.e. reported at exactly T (relMSE of an
unbiased estimator falls as 1/time). Samplers that round the count (ldsampler to a power of 4:
up to 4x the time asked) are rendered at two counts about T, and their relMSE read at T on the
line through both in log-log (--bracket; without it, the one count scaled by its time, which
favours a sampler whose error falls faster than 1/time). The table gives medians over rounds, and the variance part
of relMSE from pairs of rounds (pair_relmse: free of the reference's own noise, which matters where
the renders come near the reference, as on a GPU).

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \\
      .mi-venv/bin/python scripts/compare-mitsuba.py scenes/bench/mitsuba-rect.json \\
      --time 5 --rounds 3 --set "default=" --set "1/1 dmis=--light-samples 1 --brdf-samples 1 --diffuse-mis"
"""
import argparse
import importlib.util
import os
import re
import shlex
import statistics
import subprocess
import time

import drjit as dr
import mitsuba as mi
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location("to_mitsuba", os.path.join(HERE, "to-mitsuba.py"))
tm = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(tm)


def rgb(path):
    b = mi.Bitmap(path)
    names = [b.struct_()[i].name for i in range(b.channel_count())]
    return np.array(b, dtype=np.float64)[..., [names.index(c) for c in "RGB"]]


def relmse(img, ref):
    ok = np.all(np.isfinite(img), axis=-1)
    d = img[ok] - ref[ok]
    return float(np.mean(d * d / (ref[ok] ** 2 + 0.01)))


def pair_relmse(renders, ref, seconds):
    """The variance part of relMSE, from independent renders alone: the mean over their pairs of
    (a - b)^2 / 2 / (ref^2 + 0.01), at exactly `seconds`. The reference's own noise, which
    relmse() adds to every row alike (it matters once the renders are nearly as good as the
    reference), drops out; so does bias, which the mean / ref column shows apart."""
    es = []
    for i in range(len(renders)):
        for j in range(i + 1, len(renders)):
            (a, sa), (b, sb) = renders[i], renders[j]
            ok = np.all(np.isfinite(a) & np.isfinite(b), axis=-1)
            d = a[ok] - b[ok]
            es.append(float(np.mean(d * d / (ref[ok] ** 2 + 0.01))) / 2 * (sa + sb) / 2 / seconds)
    return statistics.mean(es) if es else float("nan")


class Mitsuba:
    def __init__(self, path, sampler="independent", light_samples=1, bsdf_samples=1):
        d = tm.convert(path, light_samples=light_samples, bsdf_samples=bsdf_samples)
        d["sensor"]["sampler"]["type"] = sampler
        self.sampler = sampler
        self.scene = tm.load(d)
        w, h = self.scene.sensors()[0].film().size()
        self.pixels = int(w) * int(h)
        t = time.time()
        self.render(1, 0)
        self.warmup_s = time.time() - t  # includes the JIT compilation
        self.rate = 1e6  # camera samples/s, refined by each timed render
        for seconds in (0.3, 1.0):  # the first renders carry fixed costs: calibrate twice
            self.timed(seconds, 0, None)

    def render(self, spp, seed):
        """At least `spp` samples per pixel: (image, samples rendered). A launch takes under 2^32
        samples (larger ones Mitsuba splits only in multiples of its wavefront, and fails
        otherwise), so a GPU's long renders go in chunks, each with a seed of its own, averaged by
        the count each really took: samplers other than `independent` round it up (ldsampler: to
        a power of two, so the chunk size is one too and never rounds past the limit)."""
        most = 1 << max(0, ((2 ** 32 - 1) // self.pixels).bit_length() - 1)
        chunks = []
        done = 0
        while done < spp:
            img = mi.render(self.scene, spp=min(most, spp - done), seed=seed * 1009 + len(chunks))
            dr.eval(img)
            n = self.scene.sensors()[0].sampler().sample_count()
            chunks.append((n, img))
            done += n
        dr.sync_thread()
        if len(chunks) == 1:
            return chunks[0][1], done
        return sum(n * np.array(img, dtype=np.float64) for n, img in chunks) / done, done

    def reference(self, seconds, out):
        """Renders of the `independent` setting, with seeds of their own, averaged by their
        counts until `seconds` have passed (one render sized from the calibration can end far
        short of it): (samples, seconds)."""
        t = time.time()
        total, acc, seed = 0, None, 999
        while time.time() - t < seconds:
            left = seconds - (time.time() - t)
            c = time.time()
            img, spp = self.render(max(1, round(min(left, 10.0) * self.rate / self.pixels)), seed)
            self.rate = spp * self.pixels / (time.time() - c)
            img = np.asarray(img, dtype=np.float64)
            acc = img * spp if acc is None else acc + img * spp
            total += spp
            seed += 1
        mi.Bitmap(np.asarray(acc / total, dtype=np.float32)).write(out)
        return total, time.time() - t

    def timed(self, seconds, seed, out):
        # A count sized from a short calibration can take a tenth of `seconds` (scaling its
        # relMSE to `seconds` would then scale the reference's noise away too): a render outside
        # [0.8, 1.25] x seconds is done again at the rate it measured, unless the sampler rounded
        # the count up (bracketed() reads that one at `seconds`).
        for _ in range(3):
            ask = max(1, round(seconds * self.rate / self.pixels))
            img, spp, wall = self.measured(ask, seed)
            self.rate = spp * self.pixels / wall
            if 0.8 * seconds <= wall <= 1.25 * seconds or spp > 1.25 * ask:
                break
        if out:
            mi.Bitmap(np.asarray(img, dtype=np.float32)).write(out)
        return spp, wall

    def measured(self, ask, seed):
        """A render of `ask` samples timed alone: (image, samples rendered, seconds). Kernels
        may take the sample count as a constant (multijitter's and ldsampler's do): a new count
        compiles them again (0.5-0.8 s on 2 cores), which a render of that count once, untimed,
        leaves out."""
        self.render(ask, seed + 7919)
        t = time.time()
        img, spp = self.render(ask, seed)
        return img, spp, time.time() - t

    def bracketed(self, seconds, seed, out):
        """timed(), and where its count took more than 1.25 seconds (the sampler rounded it up),
        also the next count below that the sampler renders: [(spp, wall, path)], longest last."""
        spp, wall = self.timed(seconds, seed, out)
        runs = [(spp, wall, out)]
        if wall <= 1.25 * seconds:
            return runs
        ask = spp // 2
        while ask >= 1:
            img, n, w = self.measured(ask, seed)
            if n < spp:
                low = out.replace(".exr", "-low.exr")
                mi.Bitmap(np.asarray(img, dtype=np.float32)).write(low)
                return [(n, w, low)] + runs
            ask //= 2
        return runs


def at_time(points, seconds):
    """The error at `seconds` on the line through [(seconds, error)] in log-log, where the two
    renders bracket `seconds` and their times differ by 1.5x or more (renders whose time is
    mostly fixed costs do not: their line would extrapolate wildly); else the render nearest
    `seconds` in log time, scaled as 1/time."""
    (t0, e0), (t1, e1) = points[0], points[-1]
    if t1 >= 1.5 * t0 and t0 <= seconds <= t1:
        k = (np.log(e1) - np.log(e0)) / (np.log(t1) - np.log(t0))
        return float(np.exp(np.log(e0) + k * (np.log(seconds) - np.log(t0))))
    t, e = min(points, key=lambda p: abs(np.log(p[0] / seconds)))
    return e * t / seconds


def illum(binary, scene, seconds, seed, options, out):
    cmd = [binary, "render", scene, "--time", str(seconds), "--spp", "1000000",
           "--seed", str(seed), "-o", out] + shlex.split(options)
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit("illum failed: %s\n%s" % (" ".join(cmd), p.stderr))
    m = re.search(r"at (\d+) spp in .* render ([0-9.]+) s \(([0-9.]+) M camera samples/s",
                  p.stderr)
    if not m:
        raise SystemExit("cannot read illum's timing line:\n" + p.stderr)
    return int(m.group(1)), float(m.group(2)), float(m.group(3))


def pairs_at_time(xs, ref, seconds):
    """pair_relmse of a setting's rounds at `seconds`: where its rounds were bracketed (the same
    counts in every round), the pairs of each count at its own mean time, then at_time()."""
    runs = [x[6] if len(x) > 6 else [(x[2], x[3], x[5])] for x in xs]
    if len({tuple(n for n, _, _ in r) for r in runs}) != 1 or len(runs[0]) == 1:
        return pair_relmse([(x[5], x[3]) for x in xs], ref, seconds)
    points = []
    for k in range(len(runs[0])):
        t = statistics.mean(r[k][1] for r in runs)
        points.append((t, pair_relmse([(r[k][2], t) for r in runs], ref, t)))
    return at_time(points, seconds)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--time", type=float, default=5.0)
    ap.add_argument("--ref-time", type=float, default=60.0)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--set", action="append", metavar="NAME=OPTIONS",
                    help="an illum option set (repeatable); default: 'default='")
    ap.add_argument("--illum", default=os.path.join(HERE, "..", "target", "release", "illum"))
    ap.add_argument("--out", default="/tmp/compare-mitsuba")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--bracket", action="store_true",
                    help="a Mitsuba count that took over 1.25 T: also render the next count "
                         "below, and read relMSE at T in log-log between both")
    ap.add_argument("--mi-sampler", default="independent",
                    help="Mitsuba's sampler: independent (its default), ldsampler (scrambled "
                         "(0,2)-sequence, power-of-two counts), multijitter, ...")
    ap.add_argument("--mi-settings", metavar="SAMPLER:L/B,...",
                    help="several Mitsuba settings (sampler, emitter and BSDF samples of its "
                         "direct integrator), e.g. independent:1/1,ldsampler:4/2; each is "
                         "rendered, and illum is compared with the best (lowest median relMSE). "
                         "Overrides --mi-sampler")
    a = ap.parse_args()
    mi.set_variant(a.variant)
    sets = [s.split("=", 1) for s in (a.set or ["default="])]
    os.makedirs(a.out, exist_ok=True)
    print("Mitsuba %s (%s, %s sampler), drjit %s, %d threads; T = %g s, reference %g s, %d rounds"
          % (mi.__version__, a.variant, a.mi_sampler, dr.__version__, dr.thread_count(), a.time,
             a.ref_time, a.rounds))
    settings = []
    for item in (a.mi_settings.split(",") if a.mi_settings else [a.mi_sampler + ":1/1"]):
        sampler, counts = item.split(":")
        light, bsdf = (int(x) for x in counts.split("/"))
        settings.append(("mitsuba %s %d/%d" % (sampler, light, bsdf), sampler, light, bsdf))
    summary = []
    for scene in a.scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        ms = {label: Mitsuba(scene, sampler, light, bsdf)
              for label, sampler, light, bsdf in settings}
        m = ms[settings[0][0]]
        ref_path = os.path.join(a.out, name + "-ref.exr")
        if not os.path.exists(ref_path):
            if m.sampler != "independent":
                raise SystemExit("the first Mitsuba setting renders the reference: independent")
            spp, wall = m.reference(a.ref_time, ref_path)
            print("%s: reference %d spp in %.1f s" % (name, spp, wall))
        ref = rgb(ref_path)
        rows = {label: [] for label in ms}
        for _ in sets:
            rows.setdefault(_[0], [])
        for r in range(a.rounds):
            for label, mm in ms.items():
                out = os.path.join(a.out, "%s-%s-%d.exr" % (name, re.sub(r"\W", "_", label), r))
                runs = mm.bracketed(a.time, r + 1, out) if a.bracket else [mm.timed(a.time, r + 1, out) + (out,)]
                imgs = [rgb(path) for _, _, path in runs]
                e = at_time([(w, relmse(img, ref)) for (_, w, _), img in zip(runs, imgs)], a.time)
                spp, wall, _ = runs[-1]
                rows[label].append((e, spp * mm.pixels / wall / 1e6, spp, wall,
                                    imgs[-1].mean() / ref.mean(), imgs[-1],
                                    [(n, w, img) for (n, w, _), img in zip(runs, imgs)]))
            for label, opts in sets:
                out = os.path.join(a.out, "%s-%s-%d.exr" % (name, re.sub(r"\W", "_", label), r))
                spp, secs, rate = illum(a.illum, scene, a.time, r + 1, opts, out)
                img = rgb(out)
                e = relmse(img, ref) * secs / a.time
                rows[label].append((e, rate, spp, secs, img.mean() / ref.mean(), img))
        best = min(ms, key=lambda k: statistics.median(x[0] for x in rows[k]))
        mine = statistics.median(x[0] for x in rows[best])
        pairs = {k: pairs_at_time(xs, ref, a.time) for k, xs in rows.items()}
        print("\n%s (Mitsuba warm-up render incl. JIT: %.2f s; best Mitsuba setting: %s)"
              % (scene, m.warmup_s, best))
        print("| renderer / illum options | relMSE at %g s | x Mitsuba | from pairs | x Mitsuba "
              "| M camera samples/s | spp | mean / ref |" % a.time)
        print("|---|---|---|---|---|---|---|---|")
        for label, xs in rows.items():
            e = statistics.median(x[0] for x in xs)
            opts = dict(sets).get(label, "")
            print("| %s%s | %.3g (%s) | %.2f | %.3g | %.2f | %.2f | %d | %.4f |"
                  % (label, " `%s`" % opts if opts else "", e,
                     ", ".join("%.3g" % x[0] for x in xs), e / mine, pairs[label],
                     pairs[label] / pairs[best],
                     statistics.median(x[1] for x in xs), statistics.median(x[2] for x in xs),
                     statistics.mean(x[4] for x in xs)), flush=True)
        # From pairs (rounds >= 2): the variance alone, free of the reference's noise.
        best_pairs = min(ms, key=lambda k: pairs[k])
        for label, _ in sets:
            summary.append((name, label, statistics.median(x[0] for x in rows[label]) / mine,
                            best, pairs[label] / pairs[best_pairs], best_pairs))
    if len(a.scenes) > 1:
        print("\n| scene | illum options | relMSE at %g s ÷ best Mitsuba | best Mitsuba setting "
              "| from pairs ÷ best Mitsuba | best Mitsuba setting (pairs) |" % a.time)
        print("|---|---|---|---|---|---|")
        for name, label, ratio, best, pratio, pbest in summary:
            print("| %s | %s | %.2f | %s | %.2f | %s |" % (name, label, ratio, best, pratio, pbest))


if __name__ == "__main__":
    main()
