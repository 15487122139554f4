"""Flight-control design against the requirement set (``study=fcs_design``): the free
parameters in physical terms (``parameters.py``) and the search over frozen operating
points and uncertainty corners (``search.py``)."""
