"""Write configs/laws/sample_truth.nc: the SYNTHETIC ground-truth friction law of the sample twin data.

    python configs/laws/make_sample_truth.py

The law is sample_data/ground_truth.yaml's (mu0 0.3, uniform injection, 100 Hz - 10 kHz, shape 1/(1+(f/1 kHz)^2),
amplitude linear in V per roughness level), built by sample_data/generate.py:truth_law and written with
fivid.friction.write_law. Studies use it as a known law; it is no identification result.
"""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "sample_data"))

from generate import load_truth, truth_law  # noqa: E402

from fivid.friction import write_law  # noqa: E402

if __name__ == "__main__":
    write_law(truth_law(load_truth()), HERE / "sample_truth.nc", overwrite=True)
