"""The analyses ``analyze`` runs: each detects from a bag's topics and types whether it
applies (``detect``) and computes its metrics and figures (``analyze``)."""
