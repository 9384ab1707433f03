"""Stage 6, the pages, rendered from saved results alone: the report tree (report), the vibration section
(vibration_page), the student's page (student_page), the LaTeX of expressions (typeset), the animation (animation),
the campaign's summary (campaign_page).  Imports the earlier stages; runs no model and imports no engine but
MuJoCo's renderer, for an animation drawn where the checks ran."""
