"""The BARN benchmark (the-barn-challenge) as its users run it: ``python -m twil_control.barn``
is run.py's equivalent, one trial per process, and many trials on Dask (barn/many.py)."""
