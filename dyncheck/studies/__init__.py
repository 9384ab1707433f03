"""Stage 5, the studies (minutes; `dyncheck report` runs them): the work-precision sweep (work_precision), the
stability studies and a case's own (stability), the Campbell diagram and the stability boundaries (campbell), the
campaign of many random parameter sets (campaign).  Each returns data; a study's figure function draws it for the
pages.  Imports the earlier stages."""
