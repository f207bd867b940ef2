"""The example script runs and writes its PNG (three budgets side by side)."""
import os
import subprocess
import sys

import pytest

from conftest import SOURCE_DIR

pytest.importorskip("matplotlib")


def test_ct_head_example(tmp_path):
    out = tmp_path / "ct_head_budgets.png"
    script = os.path.join(SOURCE_DIR, "examples", "ct_head_budgets.py")
    env = dict(os.environ, MPLBACKEND="Agg")
    p = subprocess.run([sys.executable, script, "-o", str(out)], capture_output=True, text=True,
                       env=env, timeout=600)
    assert p.returncode == 0, p.stderr
    import matplotlib.image as mpimg

    img = mpimg.imread(out)
    h, w = img.shape[:2]
    assert w > 2 * h  # three panels side by side
    # Each third of the picture has drawn (non-white) pixels.
    for k in range(3):
        panel = img[:, k * w // 3:(k + 1) * w // 3, :3]
        assert (panel < 0.9).any(axis=2).mean() > 0.02
    for n in ("2000", "10000", "40000"):
        assert n in p.stdout
