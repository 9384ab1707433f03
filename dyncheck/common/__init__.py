"""Stage 0, what every stage shares: the one line that refuses bad input and the words messages share
(messages), the arithmetic of case-file expressions (expressions), the words a number chooses (words), the ceilings
of the tolerances and the limits of one run (ceilings), the one figure style (style: the studies draw their own
figures, the pages place them) and the long stages' progress (progress).  Imports nothing of dyncheck."""
