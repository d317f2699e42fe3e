"""The peer's side of bench/tsc_peers.py, run by bench/.venv-aeon/bin/python (aeon 1.6.0 and its
pinned numpy live there, never in the project's venv); it imports nothing of Touchstone, so it
appends nothing to results/ itself: bench/tsc_peers.py records its numbers in results/tsc_peers.jsonl.

    python tsc_peers_aeon.py export OUT_DIR NAME [NAME ...]     each set's official TRAIN/TEST files from
                                                               the installed aeon package -> OUT_DIR/NAME.npz
                                                               (X, y, split = train/test)
    python tsc_peers_aeon.py run FILE.npz METHOD SEED [SEED ...]   one JSON line per seed: test accuracy,
                                                               fit s, predict ms per recording

One thread: the parent sets NUMBA_NUM_THREADS/OMP_NUM_THREADS=1, n_jobs=1 and torch's threads
are set to 1 here. Numba compiles on first use (20-60 s): every method is fitted and predicted
once on the set's first training recordings before anything is timed.
"""
import json
import sys
import time
from pathlib import Path

import numpy as np


def data_folder() -> Path:
    import aeon
    return Path(aeon.__file__).parent / "datasets" / "data"


def export(out_dir: str, names) -> None:
    from aeon.datasets import load_from_ts_file
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for name in names:
        stem = name.removesuffix("_eq")
        folder = data_folder() / stem
        parts = {side: load_from_ts_file(str(folder / f"{name}_{side.upper()}.ts")) for side in ("train", "test")}
        X = np.concatenate([np.asarray(parts[s][0], dtype=np.float64) for s in parts])
        y = np.concatenate([np.asarray(parts[s][1]).astype(str) for s in parts])
        split = np.concatenate([np.full(len(parts[s][1]), s) for s in parts])
        np.savez(out / f"{name}.npz", X=X, y=y, split=split)
        print(json.dumps({"set": name, "shape": list(X.shape), "classes": int(np.unique(y).size),
                          "n_train": int((split == "train").sum()), "n_test": int((split == "test").sum())}))


def classifier(method: str, seed: int):
    from aeon.classification.convolution_based import MiniRocketClassifier, MultiRocketHydraClassifier
    from aeon.classification.interval_based import QUANTClassifier
    if method == "minirocket":
        return MiniRocketClassifier(n_jobs=1, random_state=seed)
    if method == "multirocket_hydra":
        return MultiRocketHydraClassifier(n_jobs=1, random_state=seed)
    if method == "quant":
        return QUANTClassifier(random_state=seed)
    raise SystemExit(f"unknown method {method}")


def run(path: str, method: str, seeds) -> None:
    import torch
    torch.set_num_threads(1)
    data = np.load(path)
    X, y, split = data["X"], data["y"].astype(str), data["split"].astype(str)
    train, test = split == "train", split == "test"
    X_train, y_train, X_test, y_test = X[train], y[train], X[test], y[test]
    # Warm-up (numba compilation, torch start-up): a small fit on two recordings of every class.
    warm = np.concatenate([np.flatnonzero(y_train == c)[:2] for c in np.unique(y_train)])
    classifier(method, 0).fit(X_train[warm], y_train[warm]).predict(X_test[:2])
    for seed in seeds:
        model = classifier(method, int(seed))
        start = time.perf_counter()
        model.fit(X_train, y_train)
        fit_s = time.perf_counter() - start
        start = time.perf_counter()
        predicted = model.predict(X_test)
        bulk_ms = 1e3 * (time.perf_counter() - start) / len(X_test)
        single = []
        for k in range(min(20, len(X_test))):  # batch 1, as Touchstone's onnxruntime latency
            start = time.perf_counter()
            model.predict(X_test[k:k + 1])
            single.append(time.perf_counter() - start)
        print(json.dumps({"method": method, "seed": int(seed), "accuracy": float((predicted == y_test).mean()),
                          "fit_s": fit_s, "predict_ms_bulk": bulk_ms,
                          "predict_ms_batch1": 1e3 * float(np.median(single))}), flush=True)


if __name__ == "__main__":
    command, *args = sys.argv[1:]
    if command == "export":
        export(args[0], args[1:])
    elif command == "run":
        run(args[0], args[1], args[2:])
    else:
        raise SystemExit(f"unknown command {command}")
