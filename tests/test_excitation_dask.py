"""Multi-start through Dask: same seeds, same result as the serial run (issue 15)."""
from __future__ import annotations

import io

import numpy as np
import pytest

from excitation.fourier import FourierSeries
from excitation.multistart import dask_client, optimise_model
from test_excitation import FAST, toy_model

pytest.importorskip("dask.distributed")


def test_dask_starts_give_the_serial_result():
    model, form = toy_model(), FourierSeries(4.0, 3)
    serial = optimise_model(model, form, seed=5, starts=4, options=FAST, progress=False)
    stream = io.StringIO()
    with dask_client(workers=2, processes=False) as client:
        parallel = optimise_model(model, form, seed=5, starts=4, options=FAST, progress=stream,
                                  client=client)
    np.testing.assert_array_equal(parallel.coefficients, serial.coefficients)
    assert parallel.cond == serial.cond and parallel.info.best_start == serial.info.best_start
    assert parallel.info.total_iterations == serial.info.total_iterations
    assert sorted(line.split(":")[0] for line in stream.getvalue().splitlines()) == \
        [f"[excitation] start {k}/4" for k in range(1, 5)]


def test_dask_client_refuses_both_scheduler_and_workers():
    with pytest.raises(ValueError, match="either a scheduler address or a number of local workers"):
        with dask_client(workers=2, scheduler="tcp://127.0.0.1:1"):
            pass
