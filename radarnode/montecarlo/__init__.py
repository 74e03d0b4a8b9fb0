"""Monte Carlo evaluation of the direction-of-arrival estimators (issue 11): seed 001's experiment and metrics,
the sweeps of ``radarnode montecarlo``, and running them on all local cores or a Dask cluster."""
