#!/usr/bin/python3
"""Reads the HDF5 recordings that tests/unit/sdk/recorder_crash_test.cpp killed, with h5py, opened
as docs/recorder.md tells a reader to: plainly, and where a writer died with the file open, with
swmr=True. Prints for each file, after a tab, "rows N" (the shortest column's length, its ticks
counting 1 .. N), or what is wrong with it.
Usage: recorder_crash_read.py FILE.h5 ..."""
import sys

import h5py
import numpy


def read(path):
    try:
        recording = h5py.File(path, "r")
    except OSError:
        recording = h5py.File(path, "r", swmr=True)
    with recording:
        samples = recording["samples"]
        rows = min(samples[name].shape[0] for name in samples)
        ticks = samples["tick"][:rows]
        counting = numpy.arange(1, rows + 1, dtype=ticks.dtype)
        if not numpy.array_equal(ticks, counting):
            return f"ticks stop counting at row {int(numpy.argmin(ticks == counting))}"
        return f"rows {rows}"


for path in sys.argv[1:]:
    try:
        said = read(path)
    except Exception as error:  # every failure is the answer for this file
        said = f"error: {error}"
    print(f"{path}\t{said}")
