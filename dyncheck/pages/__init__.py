"""Stage 6, the pages, rendered from saved results alone: the report tree, index and errata (report), a case's
page (case_page) and its figures (figures), the vibration section (vibration_page), the student's page
(student_page), the LaTeX of expressions (typeset), the animation (animation), the campaign's summary
(campaign_page).  Imports the earlier stages; runs no model, and imports no engine but MuJoCo's renderer, for an
animation drawn where the checks ran (MUJOCO_GL)."""
