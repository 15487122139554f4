"""Flight-control design against the requirement set (``study=fcs_design``): the free
parameters in physical terms (``parameters.py``), the design points and their scores
(``points.py``), the search over frozen operating points and uncertainty corners
(``search.py``) and a candidate's points judged on worker processes (``pool.py``)."""
