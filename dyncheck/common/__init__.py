"""Stage 0, what every stage shares: the words of messages (messages), the arithmetic of case-file expressions
(expressions), the words a number chooses (words), the ceilings of the tolerances and the limits of a run's work
(ceilings), the one figure style (style: the studies draw their own figures, the pages place them) and the progress
of the long stages (progress).  Imports nothing of dyncheck."""
