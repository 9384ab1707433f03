"""A planar chain of n point masses on massless links (an n-link pendulum), as a case of one's own: its MJCF scene
and a plain equations.py (docs/own-case.md), for cases with as many coordinates as a test needs."""

LENGTHS = (0.31, 0.32, 0.33, 0.34, 0.35, 0.36, 0.37, 0.38, 0.39)  # m, fixed: in the scene and the derivation
# kg, each a parameter: distinct, and no other number of the scene, so that each binds to its body's mass
MASSES = (1.1, 1.2, 1.3, 1.4, 1.5, 1.6, 1.7, 1.8, 1.9)
G = 9.81

# Each mass hangs at the end of its link, at the angle theta_k from the previous link (from the downward
# vertical for the first): its absolute angle is phi_k = theta_1 + ... + theta_k, and its position
# r_k = sum_{j <= k} L_j (sin phi_j, -cos phi_j) in the plane (x, z).  With the columns c_j = L_j (cos phi_j,
# sin phi_j), dr_k/dtheta_i = sum_{i <= j <= k} c_j, and r_k'' = J_k q'' + b_k with b_k = sum_{j <= k} L_j phi_j'^2
# (-sin phi_j, cos phi_j); Newton for each mass, m_k (r_k'' + g e_z) = its links' pull, projected on the
# coordinates (virtual work, J_k^T), gives M = sum_k m_k J_k^T J_k and f = -sum_k m_k J_k^T (b_k + g e_z).
EQUATIONS = '''"""A planar chain of {n} point masses on massless links, by Newton's law projected on the joint angles."""
import numpy as np

COORDS = {coords!r}
PARAMS = {params!r}{joints}
LENGTHS = np.array({lengths!r})


def _chain(q, v, p):
    phi, rate = {angles}
    columns = LENGTHS * np.array([np.cos(phi), np.sin(phi)])  # (2, n): c_j
    bias = np.cumsum(LENGTHS * rate**2 * np.array([-np.sin(phi), np.cos(phi)]), axis=1)  # (2, n): b_k
    masses = np.array([p[f"m{{k + 1}}"] for k in range(len(q))])
    n = len(q)
    jacobians = {jacobians}
    return masses, jacobians, bias


def mass_matrix(q, p):
    masses, jacobians, _ = _chain(q, np.zeros_like(q), p)
    return sum(m * J.T @ J for m, J in zip(masses, jacobians))


def forces(t, q, v, p):
    masses, jacobians, bias = _chain(q, v, p)
    gravity = np.array([0.0, p["g"]])
    f = -sum(m * J.T @ (bias[:, k] + gravity) for k, (m, J) in enumerate(zip(masses, jacobians)))
    return f{planted}


def accelerations(t, q, v, p):
    return np.linalg.solve(mass_matrix(q, p), forces(t, q, v, p))
'''

# The same chain as generated inverse dynamics come (docs/own-case.md: tau(t, q, q', q'') = M q'' - f), a recursive
# Newton-Euler pass: the masses' accelerations outwards, r_k'' = sum_{j <= k} L_j (phi_j'' (cos, sin) + phi_j'^2
# (-sin, cos)), then each joint's moment inwards, tau_i = sum_{k >= i} (r_k - o_i) x m_k (r_k'' + g e_z) about -y.
INVERSE = '''"""A planar chain of {n} point masses on massless links, as generated inverse dynamics (a recursive
Newton-Euler pass: the masses' accelerations outwards, the joints' moments inwards)."""
import numpy as np

COORDS = {coords!r}
PARAMS = {params!r}
LENGTHS = np.array({lengths!r})


def inverse_dynamics(t, q, v, a, p):
    phi, rate, acc = np.cumsum(q), np.cumsum(v), np.cumsum(a)
    links = LENGTHS * np.array([np.sin(phi), -np.cos(phi)])  # each link, from its joint to its mass
    ends = np.cumsum(links, axis=1)  # the masses' positions r_k
    starts = ends - links  # the joints' positions o_k
    along = LENGTHS * (acc * np.array([np.cos(phi), np.sin(phi)]) + rate**2 * np.array([-np.sin(phi), np.cos(phi)]))
    masses = np.array([p[f"m{{k + 1}}"] for k in range(len(q))])
    pull = masses * (np.cumsum(along, axis=1) + np.array([[0.0], [p["g"]]]))  # m_k (r_k'' + g e_z)
    tau = np.array([np.sum((ends[0, i:] - starts[0, i]) * pull[1, i:] - (ends[1, i:] - starts[1, i]) * pull[0, i:])
                    for i in range(len(q))])
    return tau{planted}
'''


def scene(n):
    """The MJCF of the chain: link k hangs from link k-1's end by hinge theta_k about -y (a positive angle swings
    it towards +x), its mass at its end with MuJoCo's placeholder inertia."""
    inner = ""
    for k in reversed(range(n)):
        position = f' pos="0 0 -{LENGTHS[k - 1]}"' if k else ""
        inner = (f'<body name="link{k + 1}"{position}>\n<joint name="theta{k + 1}" type="hinge" axis="0 -1 0"/>\n'
                 f'<inertial pos="0 0 -{LENGTHS[k]}" mass="{MASSES[k]}" diaginertia="1e-14 1e-14 1e-14"/>\n'
                 f'{inner}</body>\n')
    return f'<mujoco model="chain{n}">\n<option gravity="0 0 -{G}"/>\n<worldbody>\n{inner}</worldbody>\n</mujoco>\n'


# The derivation in the joints' relative angles theta_k, or in absolute angles phi_k (each link's from the downward
# vertical, as a symbolic package writes a chain) over the same hinges, with the map theta_k = phi_k - phi_{k-1}
# (JOINTS, dyncheck.case.coordinate_map): then dr_k/dphi_j = c_j itself for j <= k.
RELATIVE = {"angles": "np.cumsum(q), np.cumsum(v)",  # J_k: column i is sum_{i <= j <= k} c_j, zero beyond k
            "jacobians": "[np.pad(columns[:, k::-1].cumsum(axis=1)[:, ::-1], ((0, 0), (0, n - k - 1))) for k in range(n)]"}
ABSOLUTE = {"angles": "q, v", "jacobians": "[columns * (np.arange(n) <= k) for k in range(n)]"}


def write(folder, n, planted="", absolute=False, joints=None, inverse=False):
    """The case folder of an n-link chain; `planted`: an expression added to the force side f (a numpy array),
    an error planted in the derivation; `absolute`: the derivation in absolute angles phi_k, with the map JOINTS
    (`joints`, or theta_k = phi_k - phi_{k-1}); `inverse`: as inverse dynamics (INVERSE)."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "scene.xml").write_text(scene(n))
    params = {f"m{k + 1}": MASSES[k] for k in range(n)} | {"g": G}
    if inverse:  # tau = M q'' - f: an error added to f is taken from tau
        (folder / "equations.py").write_text(INVERSE.format(
            n=n, coords=[f"theta{k + 1}" for k in range(n)], params=params, lengths=list(LENGTHS[:n]),
            planted=f" - ({planted})" if planted else ""))
        return folder
    if absolute:
        joints = joints or {f"theta{k + 1}": f"phi{k + 1} - phi{k}" if k else "phi1" for k in range(n)}
    (folder / "equations.py").write_text(EQUATIONS.format(
        n=n, coords=[f"{'phi' if absolute else 'theta'}{k + 1}" for k in range(n)], params=params,
        lengths=list(LENGTHS[:n]), planted=f" + {planted}" if planted else "",
        joints=f"\nJOINTS = {joints!r}" if absolute else "", **(ABSOLUTE if absolute else RELATIVE)))
    return folder
