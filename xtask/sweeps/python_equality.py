"""The Python package against the binary on the problems `refine.py` wrote: `curvefit.refine(**problem)`
must give the binary's points, energy and certificate bit for bit, or refuse where it refused.

    python xtask/sweeps/python_equality.py     # after refine.py, with the package installed
"""
import json, glob, os, re
import numpy as np
import curvefit
OUT = os.environ.get("SWEEP_OUT", "/tmp/curvefit-sweep/refine")
ok = diff = err_same = err_diff = 0
# (The case number from the file's name, not its path: $SWEEP_OUT may hold digits.)
case = lambda path: int(re.findall(r"\d+", os.path.basename(path))[0])
for f in sorted(glob.glob(f"{OUT}/p*.json"), key=case)[:200]:
    c = case(f); prob = json.load(open(f))
    if len(prob["points"]) > 1000: continue
    ro = f"{OUT}/r{c}.json"
    try: r = curvefit.refine(**prob); perr = None
    except curvefit.InputError as e: perr = str(e)
    if os.path.exists(ro) and os.path.getsize(ro) > 0:
        cli = json.load(open(ro))
        if perr: print("py refused, cli solved", c, perr[:100]); diff += 1; continue
        same = np.array_equal(np.asarray(cli["points"], float), r.points) and cli["energy"] == r.energy and cli["kkt_residual"] == r.kkt_residual
        ok += same; diff += (not same)
        if not same: print("DIFF", c, cli["energy"], r.energy)
    else:
        if perr: err_same += 1
        else: print("py solved, cli refused", c); err_diff += 1
print(dict(same=ok, differ=diff, both_refused=err_same, only_cli_refused=err_diff))
