"""What each key of a case file means and its unit (MEANINGS, KEY_UNITS), and the reference of the case file
generated from them and the schema: docs/case-file.md is `markdown()`; a test demands one meaning per key of
dyncheck.case.schema.SCHEMA, and no other."""

from dyncheck.case.schema import (BINDABLE, BOUNDS, MAX_ADAPTIVE_STATES, MAX_SETS, MAX_STATES, SCHEMA, joined,
                                  kind_in_words)
from dyncheck.case.units import DIMENSIONLESS, POSITIVE_UNITS
from dyncheck.common import ceilings, expressions, words

# -- the reference: docs/case-file.md ---------------------------------------------------------------
# What each key of SCHEMA means, by its dotted path: `<name>` stands for any key of a table whose keys
# are names, `[i]` for any item of an array.  A test demands one meaning per key, and no other.

ALONG_RUN = "an expression along the run (see Expressions)"
MEANINGS = {
    "name": "The case's name, an identifier; the reports and the JSON output call the case by it.",
    "section": "The book's section of the example, e.g. 1.8.3; a case of your own may have none.",
    "title": "The example's title in the reports.",
    "summary": "The example in a paragraph: the scene, its coordinates, what moves it; it opens the case's report.",
    "derivation": "Where the case's equations live: a path ending in .py of a file in the case's folder, or "
                  "`reference.<name>`, a module of the package's own `reference/` (the book's cases).  Nothing "
                  "else: a path that leaves the folder (.., an absolute path, a symbolic link to elsewhere) or any "
                  "other module is refused before anything is loaded.  It defines the sources `Book`, `Reference` "
                  "and, if the book prints a program, `Program`.",
    "coords": "The generalized coordinates, in the order of the book's equations; their rates are `<coord>_rate`.",
    "reactions": "The reactions (force or moment components) the derivation computes, by name; compared between "
                 "the sources.",
    "coord_units": "The unit of each coordinate, in the order of `coords`: rad (an angle) or m (a length).",
    "params": "The case's parameters, by name: the one source of its numbers, for the equations and both scene "
              "files alike.  `--set NAME=VALUE` overrides one.",
    "params.<name>.value": "Its default value.",
    "params.<name>.unit": "Its unit, one of the known units (see Parameters).",
    "params.<name>.about": "What it is and where the book gives it; shown in the report.",
    "params.<name>.printed": "The value as a program listing shows it in the book's text extraction, which lost "
                             "every digit 0: `\".558\"` for h = 0.0558.  It must be the value with every 0 removed; "
                             "the report shows both, and docs/book-numbers.md how each value was recovered.",
    "params.<name>.minimum": "Its value (default, override, random range) must be >= this.",
    "params.<name>.exclusive_minimum": "Its value (default, override, random range) must be > this.",
    "params.<name>.maximum": "Its value (default, override, random range) must be <= this.",
    "params.<name>.exclusive_maximum": "Its value (default, override, random range) must be < this.",
    "constraints": "What the parameters must satisfy together, beyond each one's bounds (see Constraints); `dyncheck list` shows each with its margin at the case's numbers.",
    "constraints[i].expression": "An expression of the parameters and pi that must be >= 0 (> 0 if strict).",
    "constraints[i].strict": "true: the expression must be > 0, not only >= 0.  Absent: false.",
    "constraints[i].why": "What the constraint means and why it holds; the error shows it.",
    "initial": "The initial conditions of the integrated runs.  A case of two files without them starts at rest, a "
               "tenth of a radian on every angle and a hundredth of the scene's size on every slide from its stable "
               "equilibrium at rest, where Newton-Raphson finds one from the scene's pose that holds at every time "
               "(dyncheck/case/start.py); otherwise 0.5 rad and a tenth of that size from the pose.",
    "initial.q": "The coordinates at t = 0, one per coordinate.",
    "initial.v": "Their rates at t = 0, one per coordinate.",
    "initial.t_end": "The end of the runs, which start at t = 0: a whole number of `integration.output_step`s.",
    "runaway": "Where the case's physics runs away: conditions of the parameters under which a coordinate grows "
               "without bound, so that the runs past them are reported as `runaway`, not as `unstable` (see "
               "Runaway).",
    "runaway[i].when": "A comparison of the parameters and pi that holds where the physics runs away, e.g. "
                       "`k < m*(alpha_rate + beta_rate)**2`.",
    "runaway[i].coordinate": "The coordinate that grows without bound.",
    "runaway[i].escape": "Where a run has run away: where `when` holds, every run of the checks stops at the first "
                         "step that ends with the coordinate's magnitude beyond this.",
    "runaway[i].why": "The physical reason, shown in the rows; a number in it may be written `{= expression}` "
                      "or `{= expression :format}` (an expression of the parameters), computed at the run's "
                      "parameters.",
    "sample": "The random states of the pointwise check, at which every source is evaluated.",
    "sample.count": f"How many random states (at most {MAX_STATES}).",
    "sample.budget": ("Seconds that the pointwise and equation checks may spend on their random states, for a case "
                      "whose derivation is a file of its folder: more states where a state's evaluations (the "
                      "derivation's, each engine's) are cheap, the power of two of them that fits, from `count` up "
                      f"to {MAX_ADAPTIVE_STATES} (the costs measured at the initial state). A case of two files has "
                      "0.25 s. 0, or without it: `count` states, whatever the machine's speed (a case whose report is "
                      "committed)."),
    "sample.seed": "The seed of their random generator: two runs draw the same states.",
    "sample.t": "The interval of the random times.",
    "sample.q": "The interval of each coordinate's random values, one per coordinate.",
    "sample.v": "The interval of each coordinate's random rates, one per coordinate.",
    "sample.params": "Random parameter sets of the check \"random parameters\": reference and both engines must "
                     "agree at each.",
    "sample.params.sets": f"How many parameter sets (at most {MAX_SETS}).",
    "sample.params.states": f"Random states per set (sets times states at most {MAX_STATES}).",
    "sample.params.seed": "The seed of the sets' and their states' random generator.",
    "sample.params.ranges": "The parameters that vary, by name, each drawn uniformly from its interval; the "
                            "others keep their values.  Each interval must lie within the parameter's bounds; a "
                            "set that breaks a constraint is drawn again.",
    "work_precision": "The work-precision study of `dyncheck report` (methods, steps, tolerances, the solution "
                      "they are measured against) and the convergence checks (`convergence.omega`, the scene's "
                      "fastest frequency as an expression of the parameters, sets each method's step and horizon; "
                      "an optional `convergence.method_omega` table gives a method that integrates other "
                      "coordinates its own; where the motion outruns it, four times over, the horizon ends "
                      "before, and the row says where); validated by dyncheck/studies/work_precision.py.",
    "budget": "How long a derivation of the case folder (code dyncheck does not control) may run, and in how much "
              "memory: a call, a run or a memory use past its budget is a failing row that says which function, at "
              "which state, after how long (docs/isolation.md).  The book's derivations in the package's own "
              "`reference` have none.  `run` bounds each integration, whatever it integrates.",
    "budget.call": "One call of the derivation (an accelerations, an energy, ...).  Absent: 1000 times the slowest of "
                   "its calls at the initial state, at least 5 s; its import has 60 s.",
    "budget.case": "All the checks of the case, in a process of its own.  Absent: a million times that call's cost "
                   "(what the longest runs of a case take), at least 900 s.",
    "budget.memory": "The memory the case's process may map.  Absent: the machine's memory shared by the cases that "
                     "run at once.",
    "budget.run": "The wall time of each integration of the checks (a source's run and its twin, a convergence run), "
                  "whoever's code it runs: past it the run stops, and its rows are `budget spent`, saying the budget, "
                  "what set it and how far the run got.  Absent: 4 times what the steps the run may take (its step "
                  "budget, from the case's fastest frequency) cost at the cost per step of its first 20, at least 10 s "
                  "(dyncheck/run/simulate.py).",
    "integration": "How the checks integrate the equations.",
    "integration.output_step": "The interval between a run's output rows; a multiple of mujoco_step.",
    "integration.rtol": "The relative and absolute tolerance of scipy's DOP853 for the runs of reference, book and "
                        "Pinocchio: from 100 machine epsilons (2.2e-14: scipy raises a smaller rtol to that) to "
                        f"{ceilings.RUN:g} (above it a run's error estimate means nothing).",
    "integration.tight_rtol": "The tolerance of the tight solution the runs are compared with; below rtol, and at "
                              "least 100 machine epsilons.",
    "integration.mujoco_step": "MuJoCo's fixed time step; an expression of the parameters may make it follow the scene's fastest motion (the longest step that divides an output_step of 1 ms with omega dt at most c: \"1e-3 / max(1, ceil(omega / c))\", omega written out in the parameters).",
    "tolerance": "The allowed errors of the checks, each with its argument.",
    "tolerance.pointwise": "The pointwise check: every source at the random states.",
    "tolerance.pointwise.value": f"The largest allowed relative error (at most {ceilings.POINTWISE:g}, above which "
                                 "a comparison proves nothing).",
    "tolerance.pointwise.force_scale": "The least scale a reaction is judged against (e.g. the weight m * g), so "
                                       "that a reaction that vanishes is not judged by rounding noise.",
    "tolerance.pointwise.moment_scale": "The least scale a moment reaction is judged against (e.g. the weight "
                                        "times a length); required when a reaction is a moment.",
    "tolerance.pointwise.why": "The argument for the value: rounding, modelling differences, margin.",
    "tolerance.trajectory": "The trajectory check: each integrated run against the tight solution.",
    "tolerance.trajectory.safety": f"The allowed error is this times the run's own error estimate (at most "
                                   f"{ceilings.SAFETY:g}).",
    "tolerance.trajectory.why": "The argument for the factor.",
    "tolerance.energy": "The work-energy balance check along each run.",
    "tolerance.energy.safety": f"The allowed residual is this times the balance's own error estimate (at most "
                               f"{ceilings.SAFETY:g}).",
    "tolerance.energy.why": "The argument for the factor.",
    "report": "What the case's report page says beside the checks.",
    "report.modelling": "How each source models the example: the book's equations, the reference's corrections, "
                        "the engines' scenes.",
    "report.stop": f"Where the book's program stops: {ALONG_RUN} that cuts the report's values and figures at the "
                   "first time it holds.",
    "report.values": "Values computed along every source's run, by name, shown side by side.",
    "report.values.<name>.expression": f"The value: {ALONG_RUN}, e.g. max(Rz) or first(nutation > 1).",
    "report.values.<name>.unit": "Its unit as shown (free text).",
    "report.values.<name>.about": "What it is.",
    "report.figures": "Figures drawn from every source's run, by name.",
    "report.figures.<name>.x": f"The abscissa: {ALONG_RUN}.",
    "report.figures.<name>.y": f"The ordinate: {ALONG_RUN}.",
    "report.figures.<name>.title": "The figure's title.",
    "report.figures.<name>.xlabel": "The x axis's label.",
    "report.figures.<name>.ylabel": "The y axis's label.",
    "report.figures.<name>.caption": "What the figure shows and what to see in it, under it on the page.  Absent: its title.",
    "report.figures.<name>.xlim": "The x axis's range.  Absent: the data's.",
    "report.figures.<name>.ylim": "The y axis's range.  Absent: the data's.",
    "report.figures.<name>.equal": "true: the same scale on both axes.",
    "animation": "What the case page's animation (a GIF of the motion in 3-D, or in its plane) shows beside the "
                 "motion; absent: the motion alone.",
    "animation.program": "The book's program's run (`program`) drawn `beside` the exact motion or as a `ghost` over it.",
    "animation.arrow": "A force drawn as an arrow at each frame, from the exact run; the largest is half the "
                       "scene's extent long.",
    "animation.arrow.force": f"Its three world components (x, y, z): {ALONG_RUN}.",
    "animation.arrow.at": f"The point it acts at (x, y, z, m): {ALONG_RUN}.",
    "animation.arrow.about": "What the arrow is, for the caption.",
    "animation.graph": "A quantity drawn beside the motion against time, growing with the frames, with its "
                       "largest value dashed.",
    "animation.graph.y": f"The quantity: {ALONG_RUN}.",
    "animation.graph.title": "The graph's title.",
    "animation.graph.ylabel": "Its axis's label, with the unit.",
    "animation.graph.ylim": "Its axis's range.  Absent: the data's.",
    "animation.caption": "What to see in the animation: the caption's last sentences, with measured numbers where it "
                         "says what the runs show (see Measured numbers in prose).",
    "scene": "How the scene files (scene.xml for MuJoCo, scene.urdf for Pinocchio) map to the case.",
    "scene.coords": "Each coordinate of a hinge or slide joint, by name: that joint's name in the scene files.",
    "scene.joints": "Instead of `scene.coords`, where the coordinates are not the joints' own (absolute angles over "
                    "a chain's relative hinges, another zero or sign): each hinge and slide of the scene as an affine "
                    "function of the coordinates and parameters, `{elbow = \"phi2 - phi1\"}`. The engines run in the "
                    "joints; every comparison and every named term is in the coordinates (docs/own-case.md).",
    "scene.euler": "A ball joint whose orientation the book writes in Euler angles.",
    "scene.euler.joint": "The ball joint's name in the scene files.",
    "scene.euler.coords": "The three coordinates that are its Euler angles, in the order of the book's rotations.",
    "scene.driven": "Joints that a prescribed motion moves (they are not coordinates), by name in the scene files.",
    "scene.driven.<name>.angle": "Its position at t = 0.  Absent: 0.",
    "scene.driven.<name>.rate": "Its rate at t = 0.  Absent: 0.",
    "scene.driven.<name>.acc": "Its acceleration, constant.  Absent: 0.",
    "scene.dependent": "Joints that closed kinematic loops move (MJCF <connect> equalities, docs/own-case.md section "
                       "7): no coordinate's; each engine solves them from the coordinates at every state.  Absent: none.",
    "scene.applied": "Generalized forces on joints, by name in the scene files: one per degree of freedom of the "
                     "joint (a ball joint's: moments about its local axes), each a number or a law of t, the "
                     "coordinates, their rates (`<coordinate>_rate`) and the parameters, e.g. "
                     "`x = [\"F0 * cos(Omega * t)\"]`.  The engines apply it at every evaluation (MuJoCo at each "
                     "stage of its RK4 step); its work is in the work-energy balance.",
    "scene.paths": "Bodies whose centre of mass the runs trace: the columns <body>_x, <body>_y, <body>_z of the "
                   "run (see Expressions).",
    "scene.reactions": "Where the engines read each reaction of `reactions`, by its name.",
    "scene.reactions.<name>.body": "The body the force acts on.",
    "scene.reactions.<name>.sensor": "The MJCF force (or torque) sensor that measures it, or the name of a <connect> "
                                     "for the force of its loop on its body1 at the anchor (frame \"world\").",
    "scene.reactions.<name>.axis": "Its component: 0, 1 or 2 (x, y, z).",
    "scene.reactions.<name>.frame": "The frame of the component: the body's or the world's.",
    "scene.reactions.<name>.quantity": "A force (the default: read by a <force> sensor) or a moment about the "
                                       "body's origin (a <torque> sensor on a site there), of the parent on the "
                                       "body and what hangs from it.",
    "scene.points": "Kinematic vectors of a body compared between the sources, by name: the quantities "
                    "<name>_x, <name>_y, <name>_z.",
    "scene.points.<name>.body": "The body.",
    "scene.points.<name>.frame": "The frame of the components: the body's or the world's.",
    "scene.points.<name>.kind": "What vector: the acceleration of the body frame's origin, of the centre of mass, "
                                "the angular velocity or acceleration.  Absent: acceleration.",
    "scene.urdf_root_joint": "URDF has no ball joint: Pinocchio loads scene.urdf's root link on this joint.",
    "scene.urdf_root_joint.name": "The joint's name.",
    "scene.urdf_root_joint.type": "The joint's type.",
    "scene.bindings": "Where each parameter lives in the scene files, by its name: on load the engines' models "
                      "are checked against the parameter's value, and an override is written into them.",
    "scene.bindings.<name>[i].element": "The kind of element: a body, a joint, or the option (gravity).",
    "scene.bindings.<name>[i].name": "The element's name in the scene files; gravity for the option.",
    "scene.bindings.<name>[i].attribute": "The attribute: a body's " + ", ".join(
        a for e, a in BINDABLE if e == "body") + "; a joint's " + ", ".join(
        a for e, a in BINDABLE if e == "joint") + "; none for the option.",
    "scene.bindings.<name>[i].index": "The component of a vector attribute (of fullinertia: ixx, iyy, izz, ixy, "
                                      "ixz, iyz).  Absent: 0.",
    "scene.bindings.<name>[i].scale": "The attribute is the parameter times this (e.g. -1 for gravity along -z).  "
                                      "Absent: 1.",
    "scene.bindings.<name>[i].depends": "Other parameters the attribute depends on (an inertia about the origin "
                                        "on the mass and the centre of mass): it is rewritten after them when "
                                        "they change.",
    "program": "The book's printed program (`Program` of the derivation) and its figures.",
    "program.figures": "The ranges the book's figures show, by name: the program's run and the tight solution "
                       "must stay inside.",
    "program.figures.<name>.expression": f"What the figure shows: {ALONG_RUN}.",
    "program.figures.<name>.range": "The figure's axis range.",
    "program.figures.<name>.where": "Where the book shows the figure.",
    "program.outputs": "What the program writes out, by its column: an expression of MuJoCo's values at the "
                       "program's state on the same row (see Expressions), compared at up to 200 of its rows "
                       "(check `program`, `program vs mujoco at the program's states`), e.g. `h1x = \"-link1_x\"` "
                       "where the listing's x axis is the mirror of the scene's.",
    "program.plots": "The book's figures redrawn from the program's run and the tight solution.",
    "program.plots[i].x": f"The abscissa: {ALONG_RUN}.",
    "program.plots[i].y": f"The ordinate: {ALONG_RUN}.",
    "program.plots[i].title": "The plot's title.",
    "program.plots[i].xlabel": "The x axis's label in the book's words, with its unit.  Absent: `time [s]` for t, else x.",
    "program.plots[i].ylabel": "The y axis's label in the book's words, with its unit.  Absent: the title.",
    "program.plots[i].xlim": "The x axis's range (the book's).  Absent: the data's.",
    "program.plots[i].ylim": "The y axis's range (the book's).  Absent: the data's.",
    "findings": "Errors of the book that the checks establish: a failing check that a finding covers is "
                "reported as the finding, not as a failure.",
    "findings[i].id": "A unique id, e.g. 1.8.3-R.",
    "findings[i].title": "The error in a line; it may hold measured numbers (see Measured numbers in prose), so "
                         "that it stays true under `--set`.",
    "findings[i].where": "Where the book has it.",
    "findings[i].effect": "What it changes in the book's results, where the checks cannot compute that.",
    "findings[i].sources": "The comparisons it covers: book, program, or a comparison `X vs Y` with one of them; "
                           "never an engine's or the reference's alone.",
    "findings[i].quantities": "The quantities it covers.",
    "findings[i].explanation": "The evidence: what is printed, what is right, by how much.",
    "findings[i].measured": "What this run measures of it, in sentences whose numbers are measured in the results "
                            "(see Measured numbers in prose): shown on the case page and in the errata as this run's, "
                            "never marked as the book's numbers.",
    "measured": "Numbers measured in the saved results, by name, for the pages' prose (dyncheck/results/measured.py; see "
                "Measured numbers in prose).",
    "measured.<name>.kind": "What is measured: `span` (max - min of `of` along `run`), `rms` (its root mean square "
                            "about its mean), `start`, `end`, `change` (its value at the run's first output, last, "
                            "and the difference), `phase lag` (degrees by which `run`'s oscillation of `of` lags "
                            "`against`'s, at the latter's dominant frequency over its last two periods), `frequency` "
                            "(rad/s of the vibration analysis's oscillating mode `mode`), `error` (the error of the "
                            "row with `check`, `quantity` and `sources`), `program step` (the book's program's time "
                            "step, s).",
    "measured.<name>.of": f"What is measured along the run: {ALONG_RUN}.",
    "measured.<name>.run": "The run, named as the rows name it: `program` (the book's program), `book equations, "
                           "same integrator` (the book's equations stepped as its program steps them, with the "
                           "drives' work), `tight reference` (the exact motion), `reference`, `book`, `mujoco`, "
                           "`pinocchio`.",
    "measured.<name>.against": "The run a `phase lag` is taken against (named as `run`).",
    "measured.<name>.mode": "The oscillating mode of a `frequency`, 1 the slowest.",
    "measured.<name>.source": "Whose modes a `frequency` is: reference, mujoco or pinocchio.  Absent: reference.",
    "measured.<name>.check": "The check of an `error`'s row.",
    "measured.<name>.quantity": "The quantity of an `error`'s row.",
    "measured.<name>.sources": "The comparison of an `error`'s row, as the pages write it: `program vs tight "
                               "reference`.",
    "findings[i].right": "The right expression of a printed one the search of edits does not find, by its key in "
                         "the book's module's PRINTED, in that module's symbols; the run checks it against the "
                         "reference at the random states, and the errata typeset it beside the printed one.",
    "data": "The book's printed numbers against its own formulas.",
    "data[i].name": "The quantity's name in the report.",
    "data[i].printed": "The printed value.",
    "data[i].formula": "The value of the book's formula; the difference is relative to it.",
    "data[i].where": "Where the book prints them.",
    "data[i].tolerance": f"The allowed relative difference, e.g. half a unit of the last printed digit (at most "
                         f"{ceilings.DATA:g}).",
    "data[i].relation": "equal: printed = formula; at most: printed <= formula.  Absent: equal.",
    "stability": "The stability studies of `dyncheck report`, each in a sub-table named after it; `module` names "
                 "a .py file in the case's folder (not outside it) with the case's own studies.  Validated by dyncheck/stability.",
    "vibration": "Vibration analysis (dyncheck/checks/vibration.py): an equilibrium found by Newton-Raphson, the equations "
                 "linearised about it by the derivation and by both engines, their frequencies, modes and stability, "
                 "each frequency checked in a run.  Rows with check `vibration`; the page's section \"Vibration "
                 "analysis\".",
    "course": "The student's page, `<case>_student.md` beside the case page (dyncheck/pages/student_page.py, "
              "[student-pages.md](student-pages.md)): the book's procedure step by step in plain words, each result "
              "typeset from the expression the code evaluates and checked against the engines by the run's rows.",
    "course.intro": "The page's opening paragraph: what the example is and what it finds (Markdown, `$` maths).",
    "course.steps": "The steps, in the book's order.",
    "course.steps[i].title": "The step's heading.",
    "course.steps[i].text": "What the step does, in plain words, with inline `$...$` maths, `{= expression}` "
                            "numbers (see Numbers in prose) and `{~ expression}` numbers measured in the results "
                            "(see Measured numbers in prose).",
    "course.steps[i].show": "The results the step typesets, each with its check.",
    "course.steps[i].show[i].expression": "The expression the code evaluates: `book:KEY` (the derivation's "
                                          "Book.PRINTED), `program:KEY` (Program.PRINTED), `frames:KEY` (the "
                                          "derivation module's FRAMES, matrices of the angle `a`).  Absent: a check "
                                          "alone.",
    "course.steps[i].show[i].label": "The left side, in LaTeX, e.g. `{}_{B_3}\\mathbf{a}_E`.",
    "course.steps[i].show[i].quantities": "The quantities whose rows check it.  Absent: the expression's KEY (a "
                                          "vector's name stands for its components).",
    "course.steps[i].show[i].source": "Whose rows: those comparing this source with the engines or the exact "
                                      "motion.  Absent: book or program for their expressions, else reference.",
    "course.steps[i].show[i].symbols": "LaTeX for the expression's names here, e.g. `{ a = '\\alpha' }` for a "
                                       "frame's angle.",
    "course.steps[i].show[i].checked": "What the rows compare, in words, where it is not the expression itself.",
    "course.steps[i].figures": "Figures of the case page shown in this step, each with its caption.",
    "course.steps[i].figures[i].figure": "The figure's kind: `figures/<case>_<figure>.png` of the case page "
                                         "(scene, coordinates, program, modes, ...).",
    "course.steps[i].figures[i].caption": "What it shows and what to see in it, in plain words; what it shows of "
                                          "the runs in measured numbers (see Measured numbers in prose).",
    "course.steps[i].vibration": "Show the vibration analysis's equilibrium, frequencies and stability here.",
    "vibration.why": "What is linearised, and why about this state.",
    "vibration.overrides": "Parameters changed for the linearised scene, e.g. the arm at rest so that the disk's spin "
                           "makes a relative equilibrium, or no resisting moment.",
    "vibration.q": "The coordinates where Newton-Raphson starts (one per coordinate).",
    "vibration.v": "The rates where it starts (one per coordinate): a relative equilibrium's constant rates.",
    "vibration.solve": "The state variables Newton-Raphson solves for, coordinates or `<coord>_rate`; the others "
                       "stay as given.",
    "vibration.amplitude": "The largest coordinate displacement of each mode's run from the equilibrium: small enough "
                           f"that the frequency's nonlinear shift stays below {ceilings.MOTION:g} of it.",
    "vibration.periods": "How long each mode's run lasts, in periods of that mode.",
    "vibration.campbell": "The Campbell diagram of `dyncheck report`: the frequencies against a parameter (a spin rate).",
    "vibration.campbell.parameter": "The parameter swept.",
    "vibration.campbell.scale": "What `values` are multiples of (default 1): an expression of the parameters, such as "
                                "`sqrt(k/m)`, so that the sweep follows `--set`.  Evaluated in the linearised scene (with "
                                "`vibration.overrides`) where the study runs, not on load: where it has no value there "
                                "(a square root of a negative number), or one not > 0, the page says that there is "
                                "nothing to sweep.",
    "vibration.campbell.values": "Its values, in multiples of `scale`, in order: each equilibrium starts Newton-Raphson "
                                 "from the one before.  The page's own equilibrium's value joins them where it lies "
                                 "between two.",
    "vibration.campbell.why": "What the diagram shows.",
    "vibration.boundary": "Stability boundaries, each found from the eigenvalues (bisection on the parameter between the "
                          "bracket's stable and unstable ends, or where the equilibrium ceases) and confirmed by runs "
                          "either side.",
    "vibration.boundary[i].parameter": "The parameter whose value crosses the boundary.",
    "vibration.boundary[i].scale": "What `bracket` is in multiples of (default 1), as `vibration.campbell.scale`.",
    "vibration.boundary[i].bracket": "Two values of it, in multiples of `scale`, one on each side.  Where the "
                                     "equilibrium is stable at both ends, or unstable at both, the page says so, and "
                                     "what the formula `expected` gives.",
    "vibration.boundary[i].expected": "The boundary as a formula says it is (compared with the eigenvalues'): an "
                                      "expression of the parameters, evaluated where the study runs (it may have no "
                                      "value at other parameters, as a square root of a difference).",
    "vibration.boundary[i].why": "Where the formula comes from.",
    "vibration.floquet": "About a periodic motion, where the base's motion makes the equations periodic in t (no "
                         "equilibrium): the orbit by shooting Newton-Raphson on the derivation, each source's monodromy "
                         "matrix, its Floquet multipliers and the stability verdict, the largest multiplier checked by "
                         "stroboscopic runs.  At the case's own numbers (no overrides).",
    "vibration.floquet.why": "What the periodic motion is, and why the equations are periodic.",
    "vibration.floquet.period": "The period T of the equations, an expression of the parameters and pi, e.g. "
                                "`2*pi/abs(beta_rate)` (checked: the accelerations at t and t + T agree).  Evaluated by "
                                "the analysis, not on load: where it has no value, or one not > 0, at the run's "
                                "parameters (a disk at rest, beta_rate = 0), the analysis is not applicable and says why.",
    "vibration.floquet.q": "The coordinates where shooting starts, at t = 0 (one per coordinate).",
    "vibration.floquet.v": "The rates where it starts (one per coordinate).",
    "vibration.floquet.periods": "How long the stroboscopic runs last, in periods.",
    "vibration.floquet.amplitude": "The largest coordinate displacement of the runs from the orbit, along the "
                                   "eigenvector of the largest multiplier: small enough that its nonlinear shift "
                                   f"stays below {ceilings.MOTION:g} of it.",
}
# The unit of a key's numbers, where it has one.
KEY_UNITS = {
    **dict.fromkeys(["params.<name>.value", *(f"params.<name>.{key}" for key in BOUNDS), "sample.params.ranges"],
                    "params.<name>.unit"),
    **dict.fromkeys(["initial.q", "sample.q"], "coord_units"),
    "runaway[i].escape": "the coordinate's (coord_units)",
    **dict.fromkeys(["initial.v", "sample.v"], "coord_units per s"),
    **dict.fromkeys(["initial.t_end", "sample.t", "integration.output_step", "integration.mujoco_step"], "s"),
    **dict.fromkeys(["budget.call", "budget.case", "budget.run"], "s"),
    "budget.memory": "GB (10^9 bytes)",
    "tolerance.pointwise.force_scale": "N",
    "tolerance.pointwise.moment_scale": "N m",
    "scene.driven.<name>.angle": "rad or m (the joint's)",
    "scene.driven.<name>.rate": "rad/s or m/s",
    "scene.driven.<name>.acc": "rad/s^2 or m/s^2",
    "scene.applied": "N m or N (the joint's)",
    "vibration.q": "coord_units",
    "vibration.v": "coord_units per s",
    "vibration.amplitude": "coord_units",
    **dict.fromkeys(["vibration.campbell.scale", "vibration.boundary[i].scale", "vibration.boundary[i].expected"],
                    "the parameter's"),
    **dict.fromkeys(["vibration.campbell.values", "vibration.boundary[i].bracket"], "multiples of `scale`"),
    "vibration.floquet.period": "s",
    "vibration.floquet.q": "coord_units",
    "vibration.floquet.v": "coord_units per s",
    "vibration.floquet.amplitude": "coord_units",
}


def keys(kind=SCHEMA, path=""):
    """(dotted path, type, optional) of every key of the schema, each table's keys after it."""
    tag = kind[0] if isinstance(kind, tuple) else None
    if tag == "table":
        for declared, item in kind[1].items():
            key = joined(path, declared.rstrip("?"))
            yield key, item, declared.endswith("?")
            yield from keys(item, key)
    elif tag == "map":
        yield from keys(kind[1], f"{path}.<name>")
    elif tag == "list":
        yield from keys(kind[1], f"{path}[i]")


def _words(kind):
    """A type of the schema in words."""
    if isinstance(kind, str) or kind[0] == "one of":
        return kind_in_words(kind)
    tag, *rest = kind
    return {"list": lambda: "an array, each item " + _words(rest[0]),
            "pair": lambda: "a pair [lo, hi], each " + _words(rest[0]),
            "map": lambda: "a table of names, each " + _words(rest[0]),
            "table": lambda: "a table (its keys below)",
            "free": lambda: "a table (see its meaning)"}[tag]()


def markdown():
    """docs/case-file.md: the case file's reference."""
    lines = ["# The case file", "",
             "Generated by `dyncheck.case.meanings.markdown()` from `dyncheck.case.schema.SCHEMA` and `MEANINGS`; a test checks "
             "that it is current.", "",
             "Each case is a folder (in `cases/`, or in a folder of your own given with `--cases DIR`) with its "
             "`case.toml`, `scene.xml` (MJCF, for MuJoCo), `scene.urdf` (for Pinocchio) and, if it is not elsewhere, "
             "its derivation.  Loading checks the file in this order: its keys and types (a misspelt key is refused, "
             "not taken for an absent optional one), units and cross-references; then the parameters, overrides "
             "applied, against their bounds and the constraints; then every number that may be an expression, "
             "evaluated at those parameters.  A problem gives one error naming the file, the field (a dotted path "
             "as below, or `override NAME`) and the value, and exit code 2.", "",
             "## Keys", "",
             "`<name>` stands for any key of a table whose keys are names, `[i]` for any item of an array.  A number "
             "of type \"a number or an expression in quotes\" may be written as an expression of the parameters "
             "(see Expressions); its condition (such as `> 0`) holds for its value.", "",
             "| key | required | type | unit | meaning |", "|---|---|---|---|---|"]
    lines += [f"| `{key}` | {'no' if optional else 'yes'} | {_words(kind)} | {KEY_UNITS.get(key, '')} | "
              f"{MEANINGS[key]} |" for key, kind, optional in keys()]
    lines += ["", "## Parameters", "",
              "A parameter's `unit` is any coherent SI unit (no prefix, no factor: every value of a case is in "
              "SI) that the units library pint reads, such as `N s/m`, `N m s/rad`, `kg m^2`, `rad/s^2`, or "
              f"`{DIMENSIONLESS}` for a pure number; `g`, `N/mm` or `deg` are refused with the SI unit to use.", "",
              "A parameter of the dimension of " + ", ".join(f"`{unit}` ({what})" for unit, what in POSITIVE_UNITS.items())
              + " must be > 0 in every case.  Anything else a value must satisfy depends on the case and is "
              "written next to it, in JSON Schema's words:", ""]
    lines += [f"- `{key} = x`: the value must be {relation} x" for key, relation in BOUNDS.items()]
    lines += ["", "The default `value` must lie within its bounds; so must every override (`--set`) and both "
              "ends of the parameter's interval in `sample.params.ranges`.  For example "
              "`l = { value = 0.1, unit = \"m\", exclusive_minimum = 0.0, about = \"rod length\" }`.", "",
              "## Constraints", "",
              "What no bound of one parameter can say: each `[[constraints]]` entry's `expression`, an expression "
              "of the parameters and pi, must be >= 0, or > 0 with `strict = true`.  They are checked after "
              "overrides, and at every random parameter set (a set that breaks one is drawn again).  A comparison "
              "is refused (it would pass as 0 or 1): write a >= b as `a - b`.  The error names the file, "
              "`constraints[i]`, the expression, its value, the parameters in it (marked `(override)` where "
              "overridden) and the `why`.  For example:", "",
              "```toml", "[[constraints]]", "expression = \"Ixx - m*h**2\"", "strict = true",
              "why = \"the moment of inertia about the centre of mass across the axis must be > 0\"", "```", "",
              "## Runaway", "",
              "A physical runaway is not a numerical failure.  Where the case knows its physical limits, each "
              "`[[runaway]]` entry says when the parameters are past one (`when`), which coordinate then grows "
              "without bound and where a run has run away (`escape`), and why.  At parameters where no `when` "
              "holds, nothing changes: a run that blows up is `unstable`.  Where the first `when` that holds "
              "does, every run of the checks (reference, book, Pinocchio, MuJoCo, and their twins) stops at the "
              "first step beyond `escape`, and:", "",
              "- every source escaped: the runs' rows are `runaway` (a success, counted apart), with the `why` "
              "and when, which method and which step each source escaped;",
              "- some escaped and others did not: not the physics the case states.  The rows of a run that "
              "stayed within the bound to the end fail, those of the escaped runs are `unstable` (as are those of "
              "a run that blew up otherwise: a non-finite state, a budget);",
              "- none escaped before `initial.t_end` (a growth too slow to reach `escape`): the runs are compared "
              "as at any parameters.", "",
              "The conditions are checked on load: `when` must be a comparison, and it and every `{= expression}` "
              "in `why` must evaluate at the parameters.  For example:", "",
              "```toml", "[[runaway]]", "when = \"k < m*(alpha_rate + beta_rate)**2\"", "coordinate = \"l\"",
              "escape = 100.0",
              "why = \"the spin's pull m Omega^2 = {= m*(alpha_rate + beta_rate)**2 :.4g} N/m beats the spring k = "
              "{= k :g} N/m\"",
              "```", "",
              "## Numbers in prose", "",
              "A text that a page shows (`summary`, `report.modelling`, `tolerance.<name>.why`, a finding's "
              "`explanation` and `effect`, `runaway[i].why`, ...) may write a number as `{= expression}` or "
              "`{= expression :format}` (a Python format spec of a number, default `.3g`, its width and precision of at "
              "most 3 digits each): it is computed at the parameters "
              "of the run, so that the page stays true under `--set`.  For example `sqrt(k/m) = "
              "{= sqrt(k/m) :.0f} rad/s` reads `sqrt(k/m) = 100 rad/s` at the book's k = 2000 N/m and `50 rad/s` "
              "at k = 500.  Every such number is evaluated on load (a bad one is refused, exit 2).  A number "
              "measured in the results is written `{~ ...}` (see Measured numbers in prose); one measured once, "
              "at the book's numbers, belongs only in a finding's `explanation` or `effect`, which a page under "
              "overrides marks as the case file's account of the book's numbers.", "",
              "## Measured numbers in prose", "",
              "A number measured in the results, not computed from the parameters, is named in `[measured]` and "
              "written `{~ expression}` or `{~ expression :format}`: an expression of those names and the "
              "parameters, with a number's format spec (default `.3g`) or the name of a rule of `dyncheck/common/words.py` "
              "that chooses the words from the number, such as " + "; ".join(
                  f"`{name}`: " + ", ".join(f"{x:g} \"{rule(x)}\"" for x in words.EXAMPLES[name])
                  for name, rule in words.WORDS.items())
              + ".  The pages measure them from the saved results when they are rendered; a paragraph that needs "
              "one the run could not take (its run blew up, the book's program did not finish) says so instead, "
              "and why.  They may stand in the texts a page renders beside the results: the course's texts and "
              "figure captions, `animation.caption`, a finding's `title` and `measured`.  On load each `{~ ...}` "
              "must evaluate and each measure have the keys of its kind.  For example:", "",
              "```toml", "[measured]", "l_listing = { kind = \"span\", of = \"l\", run = \"program\" }",
              "l_exact = { kind = \"span\", of = \"l\", run = \"tight reference\" }",
              "psi_lag = { kind = \"phase lag\", of = \"psi\", run = \"program\", against = \"tight reference\" }",
              "```", "",
              "with `The listing's l spans {~ l_listing :.3g} m, {~ l_listing / l_exact :ratio} the exact motion's; "
              "its swing {~ psi_lag :lag} the exact one.`, which reads \"... 0.0427 m, 14 % larger than the exact "
              "motion's; its swing lags 85 degrees behind the exact one.\" at the book's numbers.", "",
              "## Expressions", "",
              "An expression is text in quotes, parsed and evaluated by `dyncheck.common.expressions` (never by Python's "
              "eval).  It may hold only numbers, names, unary + and -, the operators + - * / **, one comparison "
              "(< <= > >= == !=, not a chain) and calls of "
              + ", ".join(f"`{name}`" for name in expressions.CALLABLE) + ".  Every number is a float; an "
              f"exponent beyond +-{expressions.MAX_EXPONENT} is refused, and so is an expression longer than "
              f"{expressions.MAX_LENGTH} characters or nested deeper than {expressions.MAX_DEPTH} levels.", "",
              "The names depend on where the expression is:", "",
              "- the file's numbers of type \"a number or an expression in quotes\", `constraints[i].expression`, "
              "`runaway[i].when` and every `{= expression}` in prose: "
              "the parameters, `pi` and numpy's " + ", ".join(f"`{name}`" for name in expressions.FUNCTIONS) + ";",
              "- along a run (`report.stop`, `report.values`, `report.figures`, `program.figures`, `program.plots`, `animation.arrow`, `animation.graph`): "
              "the run's columns, arrays over its output times (each coordinate, its rate `<coord>_rate`, each "
              "reaction, `energy`, `work`, and `<body>_x`, `<body>_y`, `<body>_z` of each body of `scene.paths`), "
              "`t`, the parameters, `pi`, numpy's " + ", ".join(f"`{name}`" for name in expressions.FUNCTIONS)
              + ", and `first(condition)`, the first time the condition holds (NaN if never).  With a "
              "`report.stop`, every array ends where it first holds;",
              "- `program.outputs`: MuJoCo's values at the program's rows' states, arrays over those rows "
              "(`<body>_x`, `<body>_y`, `<body>_z` of each body of `scene.paths` and each reaction), the parameters, "
              "`pi` and numpy's " + ", ".join(f"`{name}`" for name in expressions.FUNCTIONS) + "."]
    return "\n".join(lines) + "\n"
