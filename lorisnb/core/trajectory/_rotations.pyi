from collections.abc import Sequence

import numpy as np

def nearest(entries: Sequence[np.ndarray], thresholds: np.ndarray, q: np.ndarray, off: np.ndarray) -> None: ...
