"""Copy a run's record (config, metrics.csv, summary, eval reports without traces) into results/."""
import json, shutil, sys
from pathlib import Path

def strip(src: Path, dst: Path):
    e = json.loads(src.read_text())
    for ep in e["episodes"]:
        ep.pop("trace", None)
    dst.write_text(json.dumps(e, indent=1))

for arg in sys.argv[2:]:
    name, run = arg.split("=")
    run = Path(run); out = Path(sys.argv[1]) / name
    out.mkdir(parents=True, exist_ok=True)
    for f in ["config.toml", "metrics.csv", "summary.json"]:
        if (run / f).exists():
            shutil.copy(run / f, out / f)
    if (run / "eval.json").exists():
        strip(run / "eval.json", out / "eval.json")
    if (run / "best" / "eval.json").exists():
        strip(run / "best" / "eval.json", out / "best-eval.json")
    if (run / "best" / "best.json").exists():
        shutil.copy(run / "best" / "best.json", out / "best.json")
