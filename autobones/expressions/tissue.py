"""Layered soft tissue under the skin, solved to static equilibrium (Lee, Terzopoulos & Waters 1995, §4-7).

Below every skin triangle of the face stands a prism of three node layers: the epidermis (the skin
itself), the fascia (the bottom of the dermal-fatty layer) and the skull estimate (the bottom of
the muscle layer), along the skin's smoothed normals at the region's soft-tissue thickness.
Springs join the nodes within each layer and between layers (vertical and crossed); the
dermal-fatty springs are biphasic, soft up to a strain and stiff beyond it. Each layer keeps its
volume: a column squeezed sideways grows taller by as much (the paper's volume force pushes the
epidermal nodes along their normal by the volume lost), the squeeze spread over a few tissue
thicknesses since skin resists bending, so skin over a shortening muscle bulges. The muscles
pull the fascia along the skull; epidermis and fascia may not enter the skull and slide along it.

The paper integrates the equations of motion explicitly. Here each pose is the static equilibrium
of the same energies, found by local/global iterations (the "projective dynamics" of Bouaziz,
Martin, Liu, Kavan & Pauly 2014) with Anderson acceleration (Peng, Deng, Zhang & Zhang 2018):
every term is a squared distance to a projection (a spring to its rest length, a column to the
height that keeps its volume, a node to the skull's outside), the projections are made per
element, and one sparse system, factorised once per head, pulls them together. A pose is
therefore deterministic, and the rest pose is left exactly as it is.

Seed 000's wire deformer stays the driver (Bibliowicz 2005): the muscle force on a fascia node is
its pull, along the skull, toward where the wire-deformed skin carries it; the skull nodes follow
the bones (jaw, lids, head); epidermis and fascia find their own place above them. After the
solve: the volume the columns' own terms leave is restored as a pressure on the skin the pose
moves; no column moves further than its thickness from the wire result; the skin beyond the
tissue (the lips, whose inner surfaces face each other, the eyelids, scalp and neck) takes the
tissue's correction by a harmonic extension that fades out past its border; and no skin triangle
the wires leave the right way up is turned over.

The layered mesh itself (which skin carries tissue, the node layers, the springs, the prisms'
volumes) is built by :mod:`.tissue_mesh`; this module solves it.

Everything is canonical (+Y up, +Z front, head sizes), like :class:`~autobones.expressions.model.ExpressionModel`.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from ..errors import AutobonesError
from ..geometry.laplacian import factor_spd, laplacian
from ..geometry.normals import triangle_normals
from .tissue_mesh import area_shares, layer_areas, layer_nodes, layer_springs, prism_volumes, tissue_triangles

class TissueModel:
    """The layered tissue of Lee, Terzopoulos & Waters 1995 on one fitted expression model.

    Stiffnesses are per unit area and squared strain (strain of a spring: its length change over
    its rest length; of a node held to a target: the distance over the local tissue thickness),
    so the same numbers behave the same on any head, mesh density and unit.

    Parameters
    ----------
    dermal_fraction : float
        Depth of the fascia below the skin as a fraction of the soft-tissue thickness (the rest
        is the muscle layer, down to the skull estimate).
    epidermis, fascia, muscle_layer : float
        Spring stiffness within the epidermis, within the fascia, and of the muscle layer's
        vertical and crossed springs.
    compression : float
        Stiffness of the epidermis and fascia springs when compressed, as a fraction of their
        stiffness when stretched (skin wrinkles rather than pushes back).
    blend : float
        Distance (face units, along the skin) over which the tissue's correction fades out
        past the tissue's border.
    spread : float
        Distance, in median tissue thicknesses, over which a column's squeeze is shared with
        its neighbours (one heat-diffusion step): the bending stiffness the springs lack.
    reach : float or None
        No epidermis or fascia node ends further than this many tissue thicknesses from where
        the wires put it (None: no limit).
    dermal : (float, float)
        The biphasic dermal-fatty springs' stiffness below and above ``biphasic`` (the paper's
        30 and 70).
    biphasic : float
        Stretch (deformation ratio minus 1) where the dermal-fatty springs stiffen.
    volume : float
        Weight holding each column of each layer at the height that keeps its volume (its rest
        area times height over its current area, between half and twice its rest height: the
        volume preservation of §6; what it leaves is restored as a pressure after the solve).
    drive : float
        Weight pulling each fascia node toward where the wire-deformed skin carries it (the
        muscle forces of §5).
    rest : float
        Weight pulling each epidermal node toward the wire result (the paper's weak force
        restoring a node to its rest position).
    contact : float
        Weight of skull non-penetration (§7); the result is also projected out of the skull at the
        end, so no node is ever left inside it.
    regions : sequence of str or None
        Region labels (the rig's ``region`` field) whose skin gets tissue: the face over the
        skull and mandible. Scalp, ears and neck keep the wire result but for the fading
        correction (no expression muscle moves them, and the neck has no bone close under it);
        the eyelids too, whose skin turns with the lid joints over the eyeball, and the lips,
        thick and parted along the mouth line. None: all skin facing out of the head (also
        what a rig without a region field gets).
    iterations : int
        Local/global iterations per pose (at most).
    tolerance : float
        Stop earlier once the nodes' steps in one iteration, each over its tissue thickness,
        have a root mean square below this.
    acceleration : int
        Steps of history in the Anderson acceleration of the iterations (0: plain local/global).

    Attributes (after :meth:`fit`)
    -------------------------------
    columns_ : (c,) int64
        Welded skin vertices (``model.surface_``) that carry a tissue column.
    elements_ : (e, 3) int64
        Skin triangles of the tissue, as column indices, wound so their normal points out.
    rest_nodes_ : (3c, 3) float
        Rest nodes, layer by layer (epidermis, fascia, skull), canonical frame, head sizes.
    thickness_ : (c,) float
        Soft-tissue thickness per column, head sizes.
    rest_volume_ : float
        Total tissue volume at rest, head sizes cubed.
    """

    def __init__(self, dermal_fraction=0.4, epidermis=60.0, fascia=60.0, muscle_layer=10.0, dermal=(30.0, 70.0),
                 biphasic=0.1, volume=3000.0, drive=100.0, rest=0.5, contact=1000.0,
                 regions=("forehead", "brow", "nose", "cheeks", "chin", "jaw"), iterations=40, tolerance=2e-3,
                 acceleration=5, compression=0.1, blend=0.15, spread=2.0, reach=1.0):
        self.dermal_fraction = dermal_fraction
        self.epidermis = epidermis
        self.fascia = fascia
        self.muscle_layer = muscle_layer
        self.dermal = dermal
        self.biphasic = biphasic
        self.volume = volume
        self.drive = drive
        self.rest = rest
        self.contact = contact
        self.regions = regions
        self.iterations = iterations
        self.acceleration = acceleration
        self.compression = compression
        self.blend = blend
        self.spread = spread
        self.reach = reach
        self.tolerance = tolerance

    # ------------------------------------------------------------------------------ build
    def fit(self, model):
        """Build the layered mesh under ``model``'s skin (a fitted
        :class:`~autobones.expressions.model.ExpressionModel`) and factorise its system."""
        if not 0.0 < float(self.dermal_fraction) < 1.0:
            raise AutobonesError(f"tissue: dermal_fraction must lie in (0, 1), got {self.dermal_fraction}")
        surf = model.surface_
        cols, Fc, E0, Ns, T, X0 = layer_nodes(model, tissue_triangles(model, self.regions), self.dermal_fraction)
        nc = len(cols)
        df = float(self.dermal_fraction)

        # every column is solved for, the tissue's border too; the skin beyond it takes the
        # tissue's correction fading out over ``blend`` face units, so no step opens there
        self._extension(surf, cols, float(self.blend) * float(model.face_unit_))
        self._skin_faces, self._skin_rest_normals = surf.skin_faces, surf.rest_normals
        self._skin_adjacency = surf.adjacency

        col_area, edges, edge_area = area_shares(E0, Fc)
        springs = layer_springs(X0, edges, col_area, edge_area, self.epidermis, self.fascia, self.muscle_layer,
                                self.dermal, self.biphasic, self.compression)
        # skin resists bending: a squeezed patch bulges over a few tissue thicknesses, not column
        # by column; the height a squeeze asks for is spread by heat diffusion over ``spread``
        # median thicknesses (one implicit step, factorised once)
        Lc, Mc = laplacian(E0, Fc)
        t = (float(self.spread) * float(np.median(T))) ** 2
        self._spread_mass = Mc.tocsr()
        self._spread_solve = factor_spd((Mc + t * Lc).tocsc())
        self.springs_ = springs

        # prisms: the dermal-fatty layer over the fascia, the muscle layer over the skull; each
        # keeps its volume through the height of its columns (true layer area x height)
        self.prism_top_ = np.concatenate([Fc, nc + Fc])
        self.prism_bottom_ = np.concatenate([nc + Fc, 2 * nc + Fc])
        self.elements_ = Fc
        self.layer_rest_area_ = np.stack([layer_areas(X0, Fc, layer) for layer in range(3)])
        self.layer_height_ = np.stack([df * T, (1.0 - df) * T])
        self.column_weight_ = float(self.volume) * col_area / self.layer_height_**2    # (2, c)

        self.columns_, self.elements_ = cols, Fc
        self.rest_nodes_, self.thickness_ = X0, T
        self.skull_normals_ = Ns
        self.rest_volume_ = float(prism_volumes(X0, self.prism_top_, self.prism_bottom_).sum())
        scale = col_area / (df * T) ** 2
        self.drive_weight_ = float(self.drive) * scale
        self.rest_weight_ = float(self.rest) * scale
        self.contact_weight_ = float(self.contact) * scale
        self._factorise()
        return self

    def _across(self, up):
        """Unit mean column direction (e, 3) of each element's corners, from ``up`` (c, 3)."""
        u = up[self.elements_].sum(axis=1)
        return u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-300)

    def _factorise(self):
        """The global step's matrix over epidermis and fascia, factorised once, and the sparse
        maps that gather each term's projections into its right-hand side."""
        nc = len(self.columns_)
        N = 3 * nc
        s = self.springs_
        # unknowns: epidermis then fascia nodes; the skull nodes are placed by the bones
        free, fixed = np.arange(2 * nc), np.arange(2 * nc, N)
        ns = len(s.a)
        rows = np.concatenate([s.a, s.b])
        cols = np.tile(np.arange(ns), 2)
        # spring terms w |x_a - x_b - p|^2: incidence (N, s) weighted, +w at a and -w at b
        self._spring_rhs = sp.csr_matrix((np.concatenate([s.weight, -s.weight]), (rows, cols)), shape=(N, ns))[free]
        self._spring2_rhs = sp.csr_matrix((np.concatenate([s.weight2, -s.weight2]), (rows, cols)),
                                          shape=(N, ns))[free]
        w = s.weight + s.weight2
        L = sp.csr_matrix((np.concatenate([w, w, -w, -w]),
                           (np.concatenate([s.a, s.b, s.a, s.b]), np.concatenate([s.a, s.b, s.b, s.a]))), shape=(N, N))
        # column terms w |(x_top - x_bottom) - p|^2, one per column and layer (dermal, muscle)
        cw = self.column_weight_
        c = np.arange(nc)
        ctop, cbot = np.concatenate([c, nc + c]), np.concatenate([nc + c, 2 * nc + c])
        k = np.arange(2 * nc)
        self._column_rhs = sp.csr_matrix((np.concatenate([cw.ravel(), -cw.ravel()]),
                                          (np.concatenate([ctop, cbot]), np.tile(k, 2))), shape=(N, 2 * nc))[free]
        L = L + sp.csr_matrix((np.concatenate([cw.ravel(), cw.ravel(), -cw.ravel(), -cw.ravel()]),
                               (np.concatenate([ctop, cbot, ctop, cbot]), np.concatenate([ctop, cbot, cbot, ctop]))),
                              shape=(N, N))
        diag = np.zeros(N)
        diag[:nc] += self.rest_weight_ + self.contact_weight_
        diag[nc:2 * nc] += self.drive_weight_ + self.contact_weight_
        A = (L + sp.diags(diag)).tocsr()
        self._coupling = A[free][:, fixed]
        self._solve = factor_spd(A[free][:, free])

    def _extension(self, surf, cols, reach):
        """How the tissue's correction reaches past its border: skin vertices (welded) within
        ``reach`` (head sizes, along the skin's edges) of a column take the harmonic extension of
        the columns' correction (Laplace's equation on that band, the correction on the columns,
        zero beyond the band), which fades smoothly to nothing. Sets ``_ext_vertices`` and the
        factorised band system :meth:`_extend` solves."""
        skin_w = surf.skin_welded
        A = surf.adjacency.tocoo()
        keep = skin_w[A.row] & skin_w[A.col]
        r, c = A.row[keep], A.col[keep]
        length = np.linalg.norm(surf.vertices[r] - surf.vertices[c], axis=1)
        G = sp.csr_matrix((np.maximum(length, 1e-300), (r, c)), shape=A.shape)
        dist = dijkstra(G, directed=False, indices=cols, min_only=True, limit=reach)
        in_cols = np.zeros(len(surf.vertices), dtype=bool)
        in_cols[cols] = True
        band = np.flatnonzero(np.isfinite(dist) & ~in_cols & skin_w)
        self._ext_vertices = band
        if len(band) == 0:
            self._ext_solve = None
            return
        # the welded mesh's Laplacian (positive semi-definite), restricted to the band: Dirichlet
        # on the columns (the correction) and beyond the band (zero)
        Lp = surf.laplacian.tocsr()
        self._ext_coupling = Lp[band][:, cols]
        self._ext_solve = factor_spd(Lp[band][:, band] + sp.eye(len(band)) * 1e-12 * abs(Lp.diagonal()).max())

    def _extend(self, delta):
        """The correction (b, 3) on the band (``_ext_vertices``) from the columns' ``delta`` (c, 3)."""
        if self._ext_solve is None:
            return np.zeros((0, 3))
        return self._ext_solve(-(self._ext_coupling @ delta))

    def _keep_unfolded(self, S, P):
        """Skin ``S`` (nw, 3, welded) where no skin triangle turns over that the wire result ``P``
        (nw, 3) keeps the right way up: at the corners of such triangles the tissue's correction
        ``S - P`` is halved (a quarter off on their neighbours), again until none is left; after
        eight halvings it is dropped there (at worst the skin is ``P``). Returns the new skin and
        the fraction (nw,) of its correction each vertex kept."""
        F = self._skin_faces
        upright = self._upright(P)
        keep = np.ones(len(S))
        D = S - P
        out = S
        for k in range(len(S)):
            bad = upright & ~self._upright(out)
            if not bad.any():
                break
            hit = np.zeros(len(S), dtype=bool)
            hit[F[bad].ravel()] = True
            ring = (self._skin_adjacency @ hit.astype(np.float64) > 0) & ~hit
            keep[ring] *= 0.75
            keep[hit] *= 0.5
            keep[hit & (keep < 0.5 ** 8)] = 0.0
            out = P + keep[:, None] * D
        return out, keep

    def _pressure(self, X, weight, normal, across, passes=2):
        """Raise the epidermis of ``X`` (3c, 3, changed in place) along ``normal`` (c, 3) until the
        tissue's total volume is back to rest, each column by its share of ``weight`` (c,) times
        its area (``across``: see :func:`~autobones.expressions.tissue_mesh.layer_areas`). Returns the
        rise per column (c,)."""
        nc = len(self.columns_)
        rise = np.zeros(nc)
        area = layer_areas(X, self.elements_, 0, across)
        denom = float((weight * area).sum())
        if denom <= 0.0:
            return rise
        floor = 0.1 * self.layer_height_[0]          # a dermal layer is never pressed thinner than this
        for _ in range(passes):   # the volume is linear in the rise up to the prisms' tilt and the floor
            lost = self.rest_volume_ - float(prism_volumes(X, self.prism_top_, self.prism_bottom_).sum())
            height = np.einsum("ij,ij->i", X[:nc] - X[nc:2 * nc], normal)
            step = np.maximum(lost * weight / denom, np.minimum(floor - height, 0.0))
            X[:nc] += step[:, None] * normal
            rise += step
        return rise

    def _upright(self, S):
        """(m,) bool: the skin triangles of welded skin ``S`` (nw, 3) facing the way they do at rest."""
        return np.einsum("ij,ij->i", triangle_normals(S, self._skin_faces), self._skin_rest_normals) > 0

    # ------------------------------------------------------------------------------ pose
    def refine(self, posed, offset, rotation):
        """The tissue's equilibrium under a wire-deformed pose.

        Parameters
        ----------
        posed : (nw, 3) float
            The wire deformer's posed skin (every welded vertex of ``model.surface_``), canonical,
            head sizes.
        offset, rotation : (nw, 3) float, (nw, 3, 3) float
            The bones' motion at each welded vertex: a point ``v + u`` near rest vertex ``v`` goes
            to ``v + offset + rotation @ u`` (jaw, lids, head and neck; not the muscles).

        Returns
        -------
        skin : (nw, 3) float
            The posed skin (every welded vertex; only skin near the tissue differs from
            ``posed``), canonical, head sizes.
        info : dict
            ``iterations`` run, ``nodes`` (3c, 3) all layers' nodes, ``kept_wire`` (skin
            vertices given back the wire result, fully or half, so that no triangle the wires
            left the right way up turns over), ``volume`` (total tissue volume over rest,
            1 = kept),
            ``depth`` (the smallest height of an epidermal or fascia node above the skull, head
            sizes; never below 0).
        """
        if not hasattr(self, "_solve"):
            raise AutobonesError("TissueModel: call fit(model) before refine")
        cols, nc = self.columns_, len(self.columns_)
        T = self.thickness_
        wire = np.asarray(posed, dtype=np.float64)
        P = wire[cols]
        moved = np.asarray(offset, dtype=np.float64)[cols]
        normal, skull, drive = self._posed_columns(P, moved, np.asarray(rotation, dtype=np.float64)[cols])
        X = np.concatenate([P, drive, skull])
        step = self._local_global(X, P, normal, skull, drive)
        x, it = _anderson(step, X[:2 * nc].copy(), np.concatenate([T, T]) ** 2, int(self.iterations),
                          float(self.tolerance), int(self.acceleration))
        X[:2 * nc] = x
        # no column is pushed or pulled further than its own thickness from where the wires put
        # it: a fold the wires squeeze in (a jaw turned against the neck) bulges, but no more
        if self.reach is not None:
            corr = X[:2 * nc] - np.concatenate([P, drive])
            size = np.linalg.norm(corr, axis=1)
            limit = float(self.reach) * np.concatenate([T, T])
            X[:2 * nc] -= corr * (1.0 - np.minimum(1.0, limit / np.maximum(size, 1e-300)))[:, None]
        skin, keep = self._skin(X, wire, P, moved, normal)
        # skull non-penetration, exactly, last: what is still inside goes out along the skull normal
        skull2, up2 = np.concatenate([skull, skull]), np.concatenate([normal, normal])
        X[:nc] = skin[cols]
        X[:2 * nc] -= np.minimum(np.einsum("ij,ij->i", X[:2 * nc] - skull2, up2), 0.0)[:, None] * up2
        skin[cols] = X[:nc]
        kept = int((keep < 1.0).sum())
        depth = np.einsum("ij,ij->i", X[:2 * nc] - skull2, up2)
        info = {"iterations": it, "nodes": X, "kept_wire": kept,
                "volume": float(prism_volumes(X, self.prism_top_, self.prism_bottom_).sum() / self.rest_volume_),
                "depth": float(depth.min())}
        return skin, info

    def _posed_columns(self, P, moved, R):
        """Where the columns stand in a pose: their unit direction (c, 3) turned by the bones'
        rotations ``R`` (c, 3, 3), the skull nodes (c, 3) carried by the bones' offsets ``moved``
        (c, 3), and where the wires carry each fascia node (c, 3): under the posed skin ``P``
        (c, 3) at its rest depth, never inside the skull. Canonical, head sizes."""
        T = self.thickness_
        nc = len(P)
        # the columns turn with the bones but keep their depth: a blend of the jaw's turn and
        # the head's (linear blend skinning) would shorten them
        normal = np.einsum("nij,nj->ni", R, self.skull_normals_)
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
        skull = self.rest_nodes_[:nc] + moved - normal * T[:, None]
        # where the wires carry each fascia node (never inside the skull)
        drive = P - normal * (float(self.dermal_fraction) * T)[:, None]
        drive -= np.minimum(np.einsum("ij,ij->i", drive - skull, normal), 0.0)[:, None] * normal
        return normal, skull, drive

    def _local_global(self, X, P, normal, skull, drive):
        """The local/global iteration of a pose as a function of epidermis and fascia (2c, 3):
        ``X`` (3c, 3) the nodes (its first 2c rows overwritten by each step), ``P`` (c, 3) the
        wires' skin, ``normal`` (c, 3) the posed column directions, ``skull`` and ``drive`` (c, 3)
        from :meth:`_posed_columns`."""
        nc = len(P)
        Fc, s = self.elements_, self.springs_
        const = -(self._coupling @ skull)
        const[:nc] += self.rest_weight_[:, None] * P
        up2 = np.concatenate([normal, normal])                 # each free node's column direction
        skull2 = np.concatenate([skull, skull])
        contact = np.concatenate([self.contact_weight_, self.contact_weight_])[:, None]
        drive_w = self.drive_weight_[:, None]
        area_rest = self.layer_rest_area_[:2]
        up_s = np.where((s.a // nc != s.b // nc)[:, None], normal[s.a % nc], 0.0)   # springs between layers
        S = sp.hstack([self._spring_rhs, self._spring2_rhs, self._column_rhs]).tocsr()

        def step(x):
            """One local/global iteration from epidermis and fascia ``x`` (2c, 3): every term's
            projection, then the global solve."""
            X[:2 * nc] = x
            d = X[s.a] - X[s.b]
            length = np.sqrt(np.einsum("ij,ij->i", d, d))
            u = d / np.maximum(length, 1e-300)[:, None]
            # a spring between layers points out of the head: one pressed through itself is
            # pushed back out, not held inverted (the paper's compression penalty)
            u -= 2.0 * np.minimum(np.einsum("ij,ij->i", u, up_s), 0.0)[:, None] * up_s
            p1 = s.rest[:, None] * u
            p2 = np.minimum(length, s.limit * s.rest)[:, None] * u
            # each layer's column keeps area x height: squeezed sideways, it grows taller
            a0, a1 = layer_areas(X, Fc, 0), layer_areas(X, Fc, 1)
            squeeze = np.log(np.clip(area_rest / np.maximum(np.stack([a0, a1]), 1e-300), 0.5, 2.0))
            ratio = np.exp(self._spread_solve(self._spread_mass @ squeeze.T).T)
            v = np.concatenate([X[:nc] - X[nc:2 * nc], X[nc:2 * nc] - X[2 * nc:]])
            pc = v + ((self.layer_height_ * ratio).ravel() - np.einsum("ij,ij->i", v, up2))[:, None] * up2
            # the skull's outside; the fascia's place along the skull (its height is the tissue's)
            out = x - np.minimum(np.einsum("ij,ij->i", x - skull2, up2), 0.0)[:, None] * up2
            along = drive + np.einsum("ij,ij->i", x[nc:] - drive, normal)[:, None] * normal
            rhs = const + S @ np.concatenate([p1, p2, pc]) + contact * out
            rhs[nc:] += drive_w * along
            return self._solve(rhs)

        return step

    def _skin(self, X, wire, P, moved, normal):
        """The posed skin (nw, 3) from the solved nodes ``X`` (3c, 3, its epidermis changed in
        place) and the wires' skin ``wire`` (nw, 3; ``P`` (c, 3) at the columns), with the
        tissue's volume restored as a pressure, its correction carried past the border and nothing
        turned over that the wires left upright; and the fraction (nw,) of the correction each
        vertex kept. ``moved`` (c, 3): the bones' offsets at the columns; ``normal`` (c, 3)."""
        cols, nc = self.columns_, len(self.columns_)
        across = self._across(normal)
        # the tissue as a whole is incompressible: the volume the columns' own terms leave (their
        # stiffness against the drive, a fold held back) is taken up as a pressure on the skin the
        # pose moves, each column's epidermis rising along its normal in proportion to its motion
        motion = (np.linalg.norm(P - self.rest_nodes_[:nc] - moved, axis=1)
                  + np.linalg.norm(X[:nc] - P, axis=1))
        self._pressure(X, motion, normal, across)
        # the skin: the columns' epidermis, the correction carried past the border, then nothing
        # turned over that the wires left upright
        skin = wire.copy()
        skin[cols] = X[:nc]
        skin[self._ext_vertices] += self._extend(X[:nc] - P)
        skin, keep = self._keep_unfolded(skin, wire)
        X[:nc] = skin[cols]
        # what a held-back fold cost is restored on the skin it did not touch (undone if that folds)
        whole = keep[cols] == 1.0
        rise = self._pressure(X, motion * whole, normal, across)
        if np.any(rise):
            more = skin.copy()
            more[cols] = X[:nc]
            more[self._ext_vertices] += self._extend((rise * whole)[:, None] * normal)
            if np.all(self._upright(more) | ~self._upright(wire)):
                skin = more
        return skin, keep


def _anderson(step, x, scale2, iterations, tolerance, acceleration):
    """The fixed point of ``step`` from ``x`` (k, 3), with Anderson acceleration (Peng, Deng, Zhang &
    Zhang 2018): the next point mixes the last ``acceleration`` steps; a step whose residual grows
    restarts the history. Stops after ``iterations`` or once the steps, each row's over its
    ``scale2`` (k,) (squared), have a root mean square at most ``tolerance``. Returns the point
    and the iterations run."""
    hist_g, hist_f, prev = [], [], None
    best, it = np.inf, 0
    for it in range(1, iterations + 1):
        g = step(x)
        f = g - x
        step2 = np.einsum("ij,ij->i", f, f)          # each node's squared step, read twice
        if np.sqrt(np.mean(step2 / scale2)) <= tolerance:
            x = g
            break
        res = float(np.sqrt(step2.sum()))
        if res > best:
            hist_g, hist_f, prev = [], [], None
        best = min(best, res)
        if prev is not None and acceleration > 0:
            hist_g.append((g - prev[0]).ravel())
            hist_f.append((f - prev[1]).ravel())
            if len(hist_g) > acceleration:
                del hist_g[0], hist_f[0]
        prev = (g, f)
        if hist_f:
            gamma = np.linalg.lstsq(np.stack(hist_f, axis=1), f.ravel(), rcond=None)[0]
            x = g - (np.stack(hist_g, axis=1) @ gamma).reshape(g.shape)
        else:
            x = g
    return x, it
