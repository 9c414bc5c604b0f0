"""
``gyro-char fleet``: many recordings through the single commands' jobs on Dask (docs/fleet.md).

``inputs`` finds the devices, ``spec`` judges them against datasheet limits, ``engine`` and
``task`` run them on a Dask cluster, ``store`` keeps the outputs and the resume cache, ``table``
writes the tidy results and ``run`` ties them together.
"""
