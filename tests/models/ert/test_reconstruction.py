"""models/ert/reconstruction.py: what every ERT reconstruction shares; here the per-frame timing
the studies report as a reconstruction's cost."""
import time

import numpy as np

from models.ert.reconstruction import per_frame_ms


def test_per_frame_time_is_the_median_of_single_frame_calls():
    frames = np.arange(12.0).reshape(4, 3)
    seen = []

    def predict(batch):
        seen.append(batch.copy())
        time.sleep(0.002 if len(seen) % 5 else 0.05)      # one call in five slow: the median ignores it
        return batch

    ms = per_frame_ms(predict, frames, calls=10)
    assert len(seen) == 10 and all(batch.shape == (1, 3) for batch in seen)
    assert np.array_equal(np.vstack(seen[:4]), frames) and np.array_equal(seen[4], frames[:1])   # cycles
    assert 2.0 <= ms < 50.0
