"""Cases: one folder per scene with case.toml, scene.xml (MJCF) and scene.urdf; the case file names
where its equations (its derivation) live."""

import importlib
import importlib.util
import math
import re
import time
import tomllib
from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path
from types import MappingProxyType

import numpy as np

from dyncheck.case import derived, files, isolation, scene, schema
from dyncheck.case.halton import halton
from dyncheck.case.isolation import guarded, load_file
from dyncheck.case.coordinate_map import Mapped
from dyncheck.case.scene import PLACEHOLDER_INERTIA, PLACEHOLDER_MASS, compare_scenes
from dyncheck.common import expressions, words
from dyncheck.common.messages import suggest
from dyncheck.results import measured
from dyncheck.results.values import overrides_in_words


def settings_of(case, name):
    """The study's sub-table with its expressions evaluated (numbers stay numbers)."""
    raw = case.spec["stability"][name]
    out = {}
    for key, x in raw.items():
        if key in ("why", "methods", "initial", "overrides", "source", "method"):
            out[key] = x
        elif isinstance(x, list):
            out[key] = [case.value(y, f"stability.{name}.{key}[{i}]") for i, y in enumerate(x)]
        else:
            out[key] = case.value(x, f"stability.{name}.{key}")
    return out


CASES_DIR = Path(__file__).resolve().parents[2] / "cases"
SOURCES = ("reference", "book", "mujoco", "pinocchio")
# What a derivation's model answers at a state (docs/model-interface.md): for a plain module each it has is tried
# at the initial state on load (Case._derived), so that one that fails there is refused before any work.
INTERFACE = ("accelerations", "reactions", "energy", "drive_power", "mass_matrix", "forces")
# Scene values are parsed from decimal text by each loader; they must equal case.toml's to
# within a few ulps (binding scales are exact: +-1).
BINDING_RTOL = 4 * np.finfo(float).eps
# A fullinertia entry comes back through MuJoCo's compiler, which turns the tensor into principal moments and a
# rotation (mju_eig3, iterative) that `read` multiplies back: each entry to within 15 eps of the body's largest
# moment (measured, tests/test_scene_forms.py), however small the entry itself (an off-diagonal 0 reads back as
# 1e-19).  Allowed: 64 eps of the largest moment, 1.4e-14.  Its ceiling: a scene number that is not the case's
# differs in a printed digit, 1e-12 of the largest moment for a tensor written to 12 significant digits.
FULLINERTIA_RTOL = 64 * np.finfo(float).eps


@dataclass(frozen=True)
class Runaway:
    """A physical limit of the case that its parameters are past (a [[runaway]] whose `when` holds): the
    runs stop where they leave `bound` = (coordinate, its index, escape); `why` says why, with its numbers."""
    bound: tuple
    why: str


@dataclass(frozen=True)
class Parameter:
    """A parameter of a case as this run uses it."""
    name: str
    value: float
    default: float  # the case file's value
    unit: str
    about: str
    bounds: tuple  # (relation, value) pairs its value must satisfy (schema.demands), e.g. ((">", 0.0),)
    printed: str | None  # the default as the book's text extraction shows it, every 0 lost: ".558"

    @property
    def allowed(self):
        """The bounds in words, as the pages and `dyncheck list` show them: "> 0", or "any"."""
        return ", ".join(f"{relation} {bound:g}" for relation, bound in self.bounds) or "any"


PROSE_NUMBER = re.compile(r"\{=([^{}]*)\}")  # Case.prose
PLAIN_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")  # an override given as text


def case_names(cases_dir=CASES_DIR):
    """The case folders in `cases_dir` (each a folder holding a case.toml), by name."""
    cases_dir = Path(cases_dir)
    if not cases_dir.is_dir():
        raise ValueError(f"--cases {cases_dir}: no such folder")
    names = sorted(p.name for p in cases_dir.iterdir() if is_case_folder(p))
    if not names:  # e.g. a non-editable install, which copies the code but not cases/
        raise ValueError(f"no cases in {cases_dir} (no <folder>/case.toml, nor <folder>/{derived.SCENE} with "
                         f"<folder>/{derived.EQUATIONS}); give a folder of cases with --cases DIR")
    return names


def is_case_folder(folder):
    """A case is a folder with a case.toml, or with a scene.xml and an equations.py alone (dyncheck.case.derived)."""
    return folder.is_dir() and ((folder / "case.toml").is_file()
                                or ((folder / derived.SCENE).is_file() and (folder / derived.EQUATIONS).is_file()))


def load_case(name, cases_dir=CASES_DIR, **overrides):
    """The case `name` of `cases_dir` with parameters overridden by name; ValueError names what is wrong."""
    known = case_names(cases_dir)
    if name not in known:
        raise ValueError(f"unknown case '{name}'{suggest(name, known)}; known cases: {', '.join(known)}")
    return Case(Path(cases_dir) / name, overrides)


class Case:
    """A case: its file's numbers at its parameters (the defaults with `overrides`), its scene as the
    engines take it, and its models by source.  `spec` (the parsed file) may be given instead of read,
    as when a report is rendered from saved results (dyncheck.results.values.CaseResult.spec)."""

    def __init__(self, folder, overrides=None, spec=None, derivation=None):
        # `derivation`: the module of a case this one varies (with_params), so that one run uses one
        # version of the equations even if their file is edited meanwhile.
        self.folder = Path(folder).absolute()  # saved with the results: they must not depend on the working folder
        self.file = self.folder / "case.toml"
        # what messages name as the source of the case's numbers: its case.toml, or the folder of a case of two files
        self.origin = self.file if self.file.is_file() else self.folder
        self.spec = self._read(overrides or {}) if spec is None else spec
        schema.validate(self.spec, self.origin, self.folder if spec is None else None)
        self.name = self.spec["name"]
        self.section = self.spec.get("section", "")
        self.title = self.spec["title"]
        self.coords = tuple(self.spec["coords"])
        self.reaction_names = tuple(self.spec["reactions"])
        self.units = {k: p["unit"] for k, p in self.spec["params"].items()}
        self.defaults = {k: float(p["value"]) for k, p in self.spec["params"].items()}
        self.overrides = {}
        for key, value in (overrides or {}).items():
            if key not in self.defaults:
                raise ValueError(f"{self.origin}: case '{self.name}' has no parameter '{key}'"
                                 f"{suggest(key, self.defaults)}; its parameters are {', '.join(self.defaults)}")
            # float() reads more than numbers: "2_0" as 20, Arabic-Indic and fullwidth digits
            if isinstance(value, str) and not PLAIN_NUMBER.fullmatch(value):
                raise ValueError(f"{self.origin}: override {key} = {value!r} is not a number (a decimal in ASCII "
                                 "digits, such as 2000, 0.25 or 2e3)")
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"{self.origin}: override {key} = {value!r} is not a number") from None
            if not math.isfinite(number):
                raise ValueError(f"{self.origin}: override {key} = {number!r} is not finite")
            self.overrides[key] = number
        self.params = MappingProxyType({**self.defaults, **self.overrides})  # read-only: models get it too
        schema.check_params(self.spec, self.params, self.overrides, self.origin)
        schema.check_values(self.spec, self.origin, self.value)
        for field, text in measured.texts(self.spec, PROSE_NUMBER):  # a formula that does not evaluate: at load
            self.prose(text, field)
        measured.check(self)  # and a measured number that could not be
        q0, v0, _ = self.initial
        euler = self.spec["scene"].get("euler", {}).get("joint")
        for joint, force in self.scene.applied.items():  # a law of the state that does not evaluate: at load
            dofs = 3 if joint == euler else 1  # a ball joint's three moments, a hinge's or slide's one force
            if len(force.components) != dofs:
                raise ValueError(f"{self.origin}: scene.applied.{joint} = {list(force.components)} has "
                                 f"{len(force.components)} components; joint '{joint}' has {dofs} degree"
                                 f"{'s' * (dofs > 1)} of freedom")
            try:
                with np.errstate(all="ignore"):
                    values = force(0.0, q0, v0)
                if not np.all(np.isfinite(values)):
                    raise ValueError(f"it is {values.tolist()} at the initial state")
            except ValueError as error:
                raise ValueError(f"{self.origin}: scene.applied.{joint} = {list(force.components)}: {error}") from None
        self.findings = self.spec.get("findings", [])
        self._models = {}
        if derivation is not None:
            self.__dict__["derivation"] = derivation  # the cached_property's slot
        self._frozen = True

    def __setattr__(self, name, value):
        if getattr(self, "_frozen", False):  # a case is a value: change it with with_params
            raise AttributeError(f"a Case is frozen: cannot set {name}; use case.with_params(...)")
        super().__setattr__(name, value)

    @property
    def parameters(self):
        """Every parameter, in the case file's order."""
        return tuple(Parameter(name, self.params[name], self.defaults[name], self.units[name], item["about"],
                               tuple((relation, float(bound)) for relation, bound, _ in schema.demands(item, name)),
                               item.get("printed"))
                     for name, item in self.spec["params"].items())

    def overrides_text(self):
        """The overrides in words, as pages and rows show them: "k = 500 N/m (book: 2000)"."""
        return overrides_in_words(self.overrides, self.spec)

    def with_params(self, **params):
        """This case with further parameters overridden (on top of its own overrides)."""
        return Case(self.folder, {**self.overrides, **params}, self.spec, self.derivation)

    def runaway(self):
        """The first [[runaway]] of the case whose `when` holds at its parameters (a Runaway), or None."""
        for i, entry in enumerate(self.spec.get("runaway", [])):
            if self.value(entry["when"], f"runaway[{i}].when"):
                coordinate = entry["coordinate"]
                return Runaway((coordinate, self.coords.index(coordinate), self.value(entry["escape"])),
                               " ".join(self.prose(entry["why"], f"runaway[{i}].why").split()))
        return None

    def with_horizon(self, t_end):
        """This case with its runs ending at `t_end` (s) instead of [initial] t_end: every source's run
        from the initial conditions, the agreement horizon measured along them, and the program's run
        (ProgramUpTo).  The tolerances that depend on the horizon follow from these runs, as at the
        book's horizon; a shorter one makes a run cheap (the property tests' whole runs)."""
        spec = {**self.spec, "initial": {**self.spec["initial"], "t_end": t_end}}
        return Case(self.folder, self.overrides, spec, self.derivation)

    def _read(self, overrides):
        """The case file: case.toml as written, or, for a plain equations module beside a scene.xml, the case
        file they imply at the parameters `overrides` change (its time scales follow them), with case.toml (if
        any) over it (dyncheck.case.derived)."""
        given = self._toml() if self.file.is_file() or not (self.folder / derived.EQUATIONS).is_file() else {}
        where = given.get("derivation", derived.EQUATIONS)
        if isinstance(where, str) and where.endswith(".py") and (self.folder / derived.SCENE).is_file() \
                and files.own_file(self.folder, where, "derivation",
                                    self.file if "derivation" in given else self.folder / where).is_file():
            module = self._own_code(self.folder / where, where, f"{self.origin}: derivation = {where!r}"
                                    if "derivation" in given else str(self.folder / where))
            if derived.is_plain(module):
                from engines.mjcf import describe  # the harness reads a scene only through engines/
                mjcf = describe(self.folder / derived.SCENE)
                _, params = derived.module_values(module, self.folder / where)
                schema.check_bindings(given.get("scene", {}).get("bindings", {}), params, self.file,
                                      {"body": mjcf.masses, "joint": [j.name for j in mjcf.joints]})
                return derived.case_file(self.folder, module, mjcf, given, overrides)
        if not given:
            raise ValueError(f"{self.file}: no such file, and {self.folder / derived.EQUATIONS} defines no COORDS and "
                             "accelerations(t, q, v, p) or inverse_dynamics(t, q, v, a, p) (docs/own-case.md)")
        return given

    def _toml(self):
        try:
            with open(self.file, "rb") as f:
                return tomllib.load(f)
        except FileNotFoundError:
            raise ValueError(f"{self.file}: no such file") from None
        except OSError as error:
            raise ValueError(f"{self.origin}: cannot read it: {error.strerror}") from None
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
            raise ValueError(f"{self.origin}: not valid TOML: {error}") from None
        except RecursionError:  # tomllib recurses once per level of nested arrays and tables
            raise ValueError(f"{self.origin}: not valid TOML: nested too deeply") from None

    # -- numbers that may be expressions of the parameters --------------------
    def value(self, x, field=None):
        """A finite number from case.toml: a float, or an expression of the parameters and pi
        (dyncheck.common.expressions); `field`, where it is in the file, for the message."""
        try:
            number = float(expressions.evaluate(x, expressions.of_parameters(self.params)) if isinstance(x, str) else x)
            if not math.isfinite(number):
                raise ValueError(f"{number} is not finite")
            return number
        except (OverflowError, TypeError, ValueError) as error:  # also float() of a list, of a huge integer
            raise ValueError(f"{self.origin}: cannot evaluate {x!r}: {error}"
                             + (f" (at {field})" if field else "")) from None

    def prose(self, text, field=None):
        """`text` with each number written as `{= expression}` or `{= expression :format}` (default
        ".3g") computed at the case's parameters, so that a page's prose stays true under --set:
        "sqrt(k/m) = {= sqrt(k/m) :.0f} rad/s"."""
        def number(match):
            expression, _, spec = match[1].rpartition(":") if ":" in match[1] else (match[1], "", ".3g")
            value = self.value(expression.strip(), field)
            if not words.is_format(spec.strip()):
                raise ValueError(f"{self.origin}: {field}: cannot write {match[0]!r}: {spec.strip()!r} is not a format "
                                 "spec of a number with a width and a precision of at most 3 digits each")
            try:
                return format(value, spec.strip() or ".3g")
            except ValueError as error:  # a format spec that is not one
                raise ValueError(f"{self.origin}: {field}: cannot write {match[0]!r}: {error}") from None
        return PROSE_NUMBER.sub(number, text)

    @cached_property
    def initial(self):
        ic = self.spec["initial"]
        return (np.array([self.value(x) for x in ic["q"]]), np.array([self.value(x) for x in ic["v"]]),
                self.value(ic["t_end"]))

    def sample_states(self, count=None, stream=0):
        """The pointwise check's seeded states, a list of (t, q, v): a scrambled Halton sequence over the box of
        [sample] t, q and v, which covers it evenly (a region of 5 % of the box holds about 5 % of the states, where
        as many independent draws leave gaps and clusters).  With `count`, the first `count` of them (a point of the
        sequence does not depend on how many follow); `stream` k > 0, the k-th other sequence of the same seed
        (each random parameter set's own states)."""
        s = self.spec["sample"]
        bounds = lambda ranges: np.array([[self.value(lo), self.value(hi)] for lo, hi in ranges]).reshape(-1, 2)
        box = np.vstack([[[self.value(s["t"][0]), self.value(s["t"][1])]], bounds(s["q"]), bounds(s["v"])])
        count = self.sample_count if count is None else min(count, s["count"])
        unit = halton(len(box), count, np.random.default_rng([s["seed"], stream]))
        points = box[:, 0] + unit * (box[:, 1] - box[:, 0])
        n = len(self.coords)
        return [(float(x[0]), x[1:1 + n], x[1 + n:]) for x in points]

    @cached_property
    def sample_count(self):
        """How many random states the pointwise check takes: [sample] count, or, where [sample] budget is given (a
        case of two files has it), more where a state's evaluations are cheap: the power of two of states whose
        evaluations (state_cost) fit the budget, from count up to schema.MAX_ADAPTIVE_STATES.  A power of two: a
        cost measured a few per cent off moves the count only across a boundary, and every count's states are the
        first of the same sequence."""
        s = self.spec["sample"]
        if not s.get("budget") or not self.foreign:
            return s["count"]
        fits = 2 ** math.floor(math.log2(s["budget"] / self.state_cost()))
        return int(min(schema.MAX_ADAPTIVE_STATES, max(s["count"], fits)))

    def state_cost(self):
        """s that the pointwise and equation checks spend on one state: the derivation's accelerations (its cost,
        measured when it was loaded) and each engine's accelerations, reactions, energy and mass matrix, each the
        least of a few calls at the initial state.  The engines are the larger part where they close a loop (the
        slider-crank's: 2 ms a state, against its derivation's 0.07 ms)."""
        self.model("reference")  # measures the cost of a call of the case's own code
        q0, v0, _ = self.initial
        engines = 0.0
        for source in ("mujoco", "pinocchio"):
            model = self.model(source)
            for function in ("accelerations", "reactions", "energy", "mass_matrix"):
                call = lambda: getattr(model, function)(0.0, q0, v0)
                start = time.perf_counter()
                call()
                engines += isolation.call_cost(call, time.perf_counter() - start)
        return self.derivation.cost + engines

    @property
    def integration(self):
        return {k: self.value(v) for k, v in self.spec["integration"].items()}

    @property
    def tolerance(self):
        return self.spec["tolerance"]

    # -- the scene as the engines see it ---------------------------------------
    @cached_property
    def scene(self):
        """The scene as the engine adapters take it (dyncheck.case.scene.Scene)."""
        return scene.describe(self)

    @cached_property
    def bindings(self):
        """The parameters' places in the scene files (dyncheck.case.scene.Binding), from [scene.bindings]."""
        return scene.bindings(self.spec)

    def least_reaction_scale(self, name):
        """The least scale reaction `name` is judged against: the case's force scale, or for a moment its moment
        scale (tolerance.pointwise), so that a reaction that vanishes is not judged by rounding noise."""
        moment = self.scene.reactions[name].quantity == "moment"
        return self.value(self.tolerance["pointwise"]["moment_scale" if moment else "force_scale"])

    @property
    def driven(self):
        """Whether anything does work on the scene: prescribed motions, applied forces or dampers."""
        return bool(self.scene.driven or self.scene.applied or self.damped)

    @cached_property
    def damped(self):
        """Whether a joint of the scene has a damper: in scene.xml, or bound to a parameter that is not 0."""
        from engines.mjcf import describe  # the harness reads a scene only through engines/
        return any(self.params[b.param] for b in self.bindings if b.location.attribute == "damping") or any(
            v.location.attribute == "damping" for v in describe(self.folder / derived.SCENE).values)

    @cached_property
    def derivation(self):
        """The module of the case's equations (its `derivation`: a .py file in the case folder, or a module of
        the package's reference/), with its classes Reference, Book and, where the book prints one, Program."""
        where = self.spec["derivation"]
        path = files.derivation_file(where, self.folder, self.file)  # refused before anything runs
        if not where.endswith(".py"):
            return guarded(self._where_derived, lambda: importlib.import_module(where))
        return self._own_code(path, where, self._where_derived)

    def _own_code(self, path, where, what):
        """The module at `path`, code of the case's own folder: its calls bounded and recorded (isolation), within
        IMPORT_BUDGET until _derived has measured what one costs; `what` names it in a load's error."""
        return isolation.Guarded(load_file(path, what), f"{self.folder.name}/{where}", isolation.IMPORT_BUDGET)

    @property
    def foreign(self):
        """Whether the case's derivation is code of its own folder, not the package's `reference`: code dyncheck
        does not control, run under a budget (dyncheck.case.isolation)."""
        return isinstance(self.derivation, isolation.Guarded)

    @cached_property
    def budget(self):
        """How long the case's own code may run, a call and the whole case, and in how much memory
        (isolation.Budget; case.toml [budget], docs/isolation.md).  Memory None: the machine's, shared by the cases
        that run at once (dyncheck.cli)."""
        given = self.spec.get("budget", {})
        self.model("reference")  # measures the cost of a call of the case's own code, and sets its budget
        cost, call = (self.derivation.cost, self.derivation.budget) if self.foreign else (0.0, math.inf)
        case = given.get("case", max(isolation.CASE_FLOOR, isolation.CALLS_PER_CASE * cost))
        memory = int(given["memory"] * 1e9) if "memory" in given else None
        return isolation.Budget(float(call), float(case), memory)

    @property
    def _where_derived(self):
        """The case file's `derivation` field, as errors about the derivation name it; for a case of two files
        and no case.toml, the equations file."""
        if not self.file.is_file():
            return str(self.folder / self.spec["derivation"])
        return f"{self.origin}: derivation = {self.spec['derivation']!r}"

    @property
    def one_derivation(self):
        """Whether the case has one derivation, a researcher's own (a plain equations module, or Book =
        Reference), rather than a book's equations beside a reference that corrects them."""
        module = self.derivation
        return derived.is_plain(module) or getattr(module, "Book", None) is getattr(module, "Reference", None)

    @property
    def has_program(self):
        """Whether the book prints a program for this case (the derivation's `Program`)."""
        return hasattr(self.derivation, "Program")

    def model(self, source):
        """The model of this case by `source`: "book" | "reference" | "mujoco" | "pinocchio" | "program"."""
        if source not in SOURCES + ("program",):
            raise ValueError(f"unknown source '{source}'; sources are {', '.join(SOURCES)}, program")
        if source == "program" and not self.has_program:
            raise ValueError(f"case '{self.name}': the book prints no program for {self.section}")
        if source not in self._models:
            self._models[source] = self._build(source)
        return self._models[source]

    def approximations_doubled(self):
        """MuJoCo's scene with its approximations of the case's physics doubled: its placeholders (a mass of
        at most PLACEHOLDER_MASS, an inertia of at most PLACEHOLDER_INERTIA, where the scene means none: a
        URDF's zero; MuJoCo refuses a moving body without them) and the drift of its prescribed motions (their armature halved).  Both are small, so
        a run responds linearly to them: this scene's run minus MuJoCo's is their effect."""
        scales = {name: tuple(2.0 if held else 1.0 for held in pair) for name, pair in self.placeholders().items()}
        return self.model("mujoco").approximations_doubled(scales)

    def placeholders(self):
        """The bodies to which MuJoCo gives a placeholder where the scene means none (MuJoCo refuses a moving body
        without mass and inertia): {body: (placeholder mass?, placeholder inertia?)}, a mass of at most
        PLACEHOLDER_MASS, an inertia of at most PLACEHOLDER_INERTIA.  Not the frames between the joints of one
        body (engines.scene.moving_body), massless in both engines and no body of MuJoCo's."""
        held = {body.name: (bool(body.mass <= PLACEHOLDER_MASS),
                            bool(np.max(np.abs(body.inertia)) <= PLACEHOLDER_INERTIA))
                for body in self.model("pinocchio").tree() if not body.frame}
        return {name: pair for name, pair in held.items() if any(pair)}

    def _build(self, source):
        if source == "program":
            return ProgramUpTo(self._derived("Program"), self.initial[2])
        if source in ("book", "reference"):
            return self._derived(source.capitalize())
        if source == "mujoco":
            from engines.mujoco_adapter import MujocoModel as Model
            path = self.folder / "scene.xml"
        else:
            from engines.pinocchio_adapter import PinocchioModel as Model
            path = self.pinocchio_scene
        if not path.is_file():
            raise ValueError(f"{path}: no such scene file (case '{self.name}' needs it for {source})")
        model = Model(path, self.scene, self.writes(Model, path))
        self._verify(model, path)
        if self.scene.coordinate_map:  # the adapter runs in the joints; the checks see the case's coordinates
            model = Mapped(model, self.scene.coordinate_map)
        other = {"mujoco": "pinocchio", "pinocchio": "mujoco"}[source]
        if other in self._models:  # both engines loaded: their files must model the same scene
            engines = {source: model, other: self._models[other]}
            compare_scenes(engines["mujoco"], engines["pinocchio"], self.name)
            from engines.loops import refuse_unmatched  # the harness reads a scene only through engines/
            # a loop closed in one file only would be locked or free in the other engine
            refuse_unmatched(engines["mujoco"].loops.loops, engines["pinocchio"].loops.loops,
                             engines["mujoco"].path, engines["pinocchio"].path)
        return model

    def writes(self, Model, path):
        """The (location, value) pairs that an adapter `Model` writes into the scene file at `path`: the file must
        already hold the defaults, so what it cannot hold (Model.elements_in), and the overrides.  A location that
        `depends` on other parameters (an inertia about the origin depends on the mass and the centre of mass) is
        rewritten when they change, after them."""
        changed = lambda b: b.param in self.overrides or set(b.depends) & set(self.overrides)
        return [(b.location, self.params[b.param] * b.scale)
                for b in sorted(self.bindings, key=lambda b: bool(b.depends))
                if changed(b) or b.location.element not in Model.elements_in(path)]

    @property
    def pinocchio_scene(self):
        """The scene file Pinocchio reads: a hand-written scene.urdf, a second model of the scene checked against
        the MJCF on load, or else the MJCF itself (Pinocchio's own MJCF reader)."""
        urdf = self.folder / "scene.urdf"
        return urdf if urdf.is_file() else self.folder / derived.SCENE

    def _derived(self, name):
        """The derivation's class `name` at the case's parameters, checked against the case file: its
        coordinates and reactions, and at the initial state the shape of its accelerations and, for a plain module,
        every function of INTERFACE it has (whose answers must be real numbers of their shapes: derived.real)."""
        what = self._where_derived
        cls = getattr(self.derivation, name, None)
        if derived.is_plain(self.derivation) and name != "Program":  # one derivation: the equations under test
            cls = lambda params: derived.Equations(self.derivation, params, self.reaction_names)
        if cls is None:
            raise ValueError(f"{what} defines no class {name} (docs/model-interface.md)")
        own = self.derivation if self.foreign else None  # the case's own code, bounded (isolation)
        model = guarded(f"{what}: {name}({{params}})", lambda: cls(self.params) if own is None else
                        isolation.guarded_call(own.label, name, own.budget, cls, self.params))
        if own is not None and not isinstance(model, derived.Equations):  # a class of the case's own code
            model = derived.Checked(isolation.Guarded(model, own.label, own.budget), len(self.coords))
        coords, reactions = getattr(model, "coords", None), getattr(model, "reaction_names", None)
        if coords is None or tuple(coords) != self.coords:
            raise ValueError(f"{what}: {name}.coords is {coords!r}, but case.toml's coords are {list(self.coords)}")
        # a printed program may compute fewer reactions than the case compares
        if reactions is None or not set(reactions) <= set(self.reaction_names) or \
                (name != "Program" and tuple(reactions) != self.reaction_names):
            raise ValueError(f"{what}: {name}.reaction_names is {reactions!r}, but case.toml's reactions are "
                             f"{list(self.reaction_names)}")
        q0, v0, _ = self.initial
        answers = {}
        # A class may decline a question on purpose (a printed program computes no energy: NotImplementedError),
        # which its rows then say; a plain module's functions (derived.Equations) are all meant as answers.
        asked = [f for f in INTERFACE if callable(getattr(model, f, None))] if isinstance(model, derived.Equations) \
            else ["accelerations"]
        for function in asked:
            try:
                with np.errstate(all="ignore"):
                    start = time.perf_counter()
                    answers[function] = getattr(model, function)(0.0, q0, v0)
                    if own is not None and name == "Reference" and function == "accelerations":
                        own.cost = isolation.call_cost(lambda: model.accelerations(0.0, q0, v0),
                                                       time.perf_counter() - start)
                        own.budget = self.spec.get("budget", {}).get(
                            "call", max(isolation.CALL_FLOOR, isolation.CALLS_PER_BUDGET * own.cost))
            except (ArithmeticError, np.linalg.LinAlgError):  # absurd parameters: the checks' rows say where
                return model
            except Exception as error:  # also what a plain module returns that is not real numbers (derived.real)
                raise ValueError(f"{what}: {name}.{function} at the initial state: {type(error).__name__}: "
                                 f"{error}") from None
        acc = np.asarray(answers["accelerations"], dtype=float)
        if acc.shape != (len(self.coords),):
            raise ValueError(f"{what}: {name}.accelerations gives shape {acc.shape} at the initial state, not "
                             f"({len(self.coords)},), one per coordinate")
        return model

    def _verify(self, model, path):
        """Refuse an engine model whose masses, lengths, springs, dampers or gravity differ from the case."""
        for binding in self.bindings:
            location, param = binding.location, binding.param
            expected = self.params[param] * binding.scale
            found = model.read(location)
            if location.attribute == "fullinertia":  # to within the rounding of the body's largest moment
                largest = max(abs(model.read(replace(location, index=i))) for i in range(3))
                allowed = FULLINERTIA_RTOL * max(abs(expected), largest)
            else:
                allowed = BINDING_RTOL * max(abs(expected), abs(found))
            if abs(found - expected) > allowed:
                raise ValueError(f"{path.name} of case '{self.name}': {location.text()} is {found!r}, but "
                                 f"{self._given_by(param)} gives {param} = {self.params[param]!r}"
                                 + (f" (x {binding.scale})" if binding.scale != 1.0 else ""))

    def _given_by(self, param):
        """What gives the value of parameter `param`, as a message names it: an override, the case.toml that
        sets it, or else, for a case whose case file is derived from a plain module, that module's PARAMS."""
        if param in self.overrides:
            return "the override"
        if derived.is_plain(self.derivation) and not (self.file.is_file() and param in self._toml().get("params", {})):
            return f"{self.spec['derivation']}'s PARAMS"
        return self.file.name

    def __repr__(self):
        return f"Case({self.name!r}, overrides={self.overrides})"


class ProgramUpTo:
    """A case's Program, its run cut at the case's [initial] t_end, where every run of the case ends:
    a listing runs as long as the book's, which Case.with_horizon may shorten (the program checks
    compare over the run's length).  The book's listings end within their case's t_end."""

    def __init__(self, program, t_end):
        self.program, self.t_end = program, t_end

    def __getattr__(self, name):
        return getattr(self.program, name)

    def run(self, q0, v0):
        return self.program.run(q0, v0).loc[:self.t_end]


#END
