"""Stage 3, running a model: integration by scipy, fixed steps and MuJoCo's own, the methods, their budgets and
a blow-up recorded as data (simulate), the tight solutions kept across runs (cache).  Imports the earlier stages
(dyncheck.common, dyncheck.results, dyncheck.case)."""
