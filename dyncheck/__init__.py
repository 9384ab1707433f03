"""dyncheck: the worked examples of 'Dynamics of Machines' ch. 1 against MuJoCo and Pinocchio."""

from dyncheck.case import Case, case_names, load_case

__all__ = ["Case", "case_names", "load_case"]
