"""The mechanism's joints as a table, and the registered joint types (docs/architecture.md,
"The joint table", "Joint types").

Plain data, read when the kernel is imported: the number of joints :data:`N_JOINTS` sizes
the per-joint blocks of ``layout`` (``D_*``, ``M_*``), the per-joint work arrays and the
per-joint loops of ``rk4`` and ``dopri5``; each joint's clearance parameters are its row
of the packed ``jp`` (``layout.J_*``), in the table's order. A joint type is one module of
``core/`` that declares ``JOINT_TYPE`` and ``CONTACTS`` and compiles :data:`PROVIDES`
with the signatures of :data:`PROTOCOL` (its gap and contact; the wear surface of a
one-point contact, its caps and their deposit; a multi-contact type's steps, deposit and
penetrations; the Poincare section's offsets; the seated start; its force's stiff rate);
it is registered in
:data:`JOINT_TYPES` (tests/test_joints.py fails for a module that is not, or a
registration without its module, functions, signatures or docs). The integrators reach
the types through ``jointkinds``, which reads each row's type here and dispatches on it:
they name no joint. ``dynamics`` applies each joint's contact through it too
(``jointkinds.contact``, ``jointkinds.multi_contact``), calling no type's contact by name.

What the table does not drive yet: ``dynamics.evaluate`` (the RSSP's equations of motion,
the one kernel module that names its joints) applies joint A (crank pin in the rod), joint
B (rod end in the slider), joint O (crank journal in the ground's bearing) and joint P (the
slider's block in the ground's guide) by name, with the attachment points written there as
in :data:`JOINTS`, and removes the crank's rotation and the slider's guide analytically
over the free coordinates of :data:`FREE` (the crank's two in the bearing plane counting
only where O has clearance, the slider's two across its guide only where P has,
``dynamics.minv_apply``); tests/test_joints.py checks the table's attachments against the
packed initial state and :data:`FREE` against the solve's columns.
"""

from collections import namedtuple

#: A body of the mechanism: its name and where its centroid and Euler angles sit in the
#: state vector (``layout.Y_*``: 3 values each).
Body = namedtuple("Body", ["name", "y_r", "y_phi"])

#: The bodies, in state order (crank 2, rod 3, slider 4); the ground (body 1) has no state
#: (``y_r``, ``y_phi`` None: it stays at the origin, unrotated).
BODIES = (Body("crank", 0, 3), Body("rod", 6, 9), Body("slider", 12, 15),
          Body("ground", None, None))

#: A point fixed in a body, in the body's frame [m]: ``length`` names the packed length it
#: scales (``"l2"``: crank, ``"l3"``: rod, ``"zs"``: the guide's height, None: the point is
#: the centroid) and
#: ``factors`` the three multiples of that length.
Attachment = namedtuple("Attachment", ["body", "length", "factors"])

#: A joint of the mechanism: its name (the config key ``joints.<name>`` and the suffix of
#: its output variables), its type (a key of :data:`JOINT_TYPES`), where the ball sits
#: (on which body, at which point) and where the socket sits.
Joint = namedtuple("Joint", ["name", "type", "ball", "socket"])

#: The mechanism's joints, in the order of the per-joint rows and blocks (jp, s, the
#: wear maps, the D_* and M_* pairs).
JOINTS = (
    Joint("A", "spherical", ball=Attachment("crank", "l2", (0.0, 0.0, -0.5)),
          socket=Attachment("rod", "l3", (-0.5, 0.0, 0.0))),
    Joint("B", "spherical", ball=Attachment("rod", "l3", (0.5, 0.0, 0.0)),
          socket=Attachment("slider", None, (0.0, 0.0, 0.0))),
    # the crank's journal (its "ball": the crank end on the crank axis) in the ground's
    # bearing at the origin, axis along global x
    Joint("O", "revolute", ball=Attachment("crank", "l2", (0.0, 0.0, 0.5)),
          socket=Attachment("ground", None, (0.0, 0.0, 0.0))),
    # the slider's block (its "ball": the block's centroid) in the ground's guide along
    # global x at the height z_s (the socket's attachment: the guide's axis at x = 0; the
    # block moves freely along it, and its offset across it is (y4, z4 - z_s))
    Joint("P", "prismatic", ball=Attachment("slider", None, (0.0, 0.0, 0.0)),
          socket=Attachment("ground", "zs", (0.0, 0.0, 1.0))),
)

#: Joints of the mechanism.
N_JOINTS = len(JOINTS)

#: The joints whose type the planar slider-crank (``mechanism.kind: slider_crank``,
#: docs/mechanisms.md) changes from the table's: its crank pin A and wrist pin B are pins
#: in bearings (revolute), not balls in sockets; O and P keep the table's types.
SLIDER_CRANK_TYPES = {"A": "revolute", "B": "revolute"}

#: In the slider-crank, each body's two axes (indices into its frame) that span the
#: mechanism's plane (global y, z) in that order, the third along the bearings' axis
#: (global x), right-handed with them: the rod's x (along the rod) and z (its alpha held at
#: pi/2, ``dynamics.planar_rod``: its y axis along -x); the crank's, slider's and ground's
#: y and z. A revolute joint whose bearing sits in a moving body reads its map in these
#: (``revolute.gap``).
PLANE_AXES = {"crank": (1, 2), "rod": (0, 2), "slider": (1, 2), "ground": (1, 2)}


def row_types(slider_crank: bool) -> tuple[str, ...]:
    """Each row's type (a key of :data:`JOINT_TYPES`), in the table's order, in the RSSP
    (the table's) or, with ``slider_crank``, in the planar slider-crank
    (:data:`SLIDER_CRANK_TYPES`)."""
    own = SLIDER_CRANK_TYPES if slider_crank else {}
    return tuple(own.get(joint.name, joint.type) for joint in JOINTS)

#: A free coordinate of the equations of motion: a column of the ideal joints' constraint
#: rows and of the free coordinates' mass matrix (``dynamics.NZ`` of them, in this order).
#: ``body`` names the body it moves, ``axis`` the global axis of a centroid coordinate
#: (``"x"``, ``"y"``, ``"z"``) or the Euler angle it is (``"alpha"``, ``"beta"``), and
#: ``freed_by`` the joint whose clearance or bushing frees it (None: free in every build;
#: elsewhere the coordinate is held, its inverse mass 0).
FreeCoordinate = namedtuple("FreeCoordinate", ["name", "body", "axis", "freed_by"])

#: The free coordinates of the equations of motion. The crank is driven and the rod's spin
#: is fixed (gamma3 = 0), so the rod's centroid and two angles and the slider's position
#: along its guide are always free; the crank's centroid in the bearing's plane only where
#: O lets it move, and the slider across its guide only where P does (their angles then
#: follow from the slider's own rotational equations). The coordinates a joint frees come
#: last, P's last of all: a build without P's clearance loops over the first ones only
#: (``dynamics.NZ_HELD``). The names are the RSSP's; the planar slider-crank's guide runs
#: along y, so its columns read: "x4" its y4 along the guide, "y4" its x4 across the plane
#: (held with its angles alpha4, beta4 where P has clearance: ``dynamics.planar_slider``;
#: no row reaches the column), "z4" its z4.
FREE = (
    FreeCoordinate("x3", "rod", "x", None),
    FreeCoordinate("y3", "rod", "y", None),
    FreeCoordinate("z3", "rod", "z", None),
    FreeCoordinate("alpha3", "rod", "alpha", None),
    FreeCoordinate("beta3", "rod", "beta", None),
    FreeCoordinate("x4", "slider", "x", None),
    FreeCoordinate("y2", "crank", "y", "O"),
    FreeCoordinate("z2", "crank", "z", "O"),
    FreeCoordinate("y4", "slider", "y", "P"),
    FreeCoordinate("z4", "slider", "z", "P"),
)

#: Each joint's row by name (``INDEX["O"]``: the revolute joint's row of jp, s, the maps).
INDEX = {joint.name: i for i, joint in enumerate(JOINTS)}

#: Registered joint types: type name -> the module of ``clearsweep.core`` that implements
#: it (that module's ``JOINT_TYPE`` is the name).
JOINT_TYPES = {"spherical": "spherical", "revolute": "revolute", "prismatic": "prismatic",
               "bushing": "bushing"}

#: One function of the joint-type protocol (docs/architecture.md, "Joint types"): its name,
#: its parameters in order, the names of the values it returns (a tuple of that length), and
#: what it computes.
Protocol = namedtuple("Protocol", ["name", "params", "returns", "doc"])

#: The protocol every joint type compiles, with these signatures whatever the type
#: (tests/test_joints.py checks each registered module's functions against it, names,
#: parameters and the length of what they return: a tuple of that length, a single value
#: where one is named). A joint touches its socket at one point (spherical, revolute) or at
#: several (prismatic: 16 corner-wall slots); ``k`` indexes them (0 for a one-point type),
#: and the module's ``CONTACTS`` says how many (0: a type that never touches, the bushing).
#: A parameter a type has no use for is taken and not read (revolute's and prismatic's
#: ``Rs``: their socket frame is the global frame); a function a type has nothing to do in
#: returns the neutral value its doc names. The kernel reaches them through
#: ``jointkinds``, which dispatches on each row's type of :data:`JOINTS`: ``rk4`` and
#: ``dopri5`` name no joint.
PROTOCOL = (
    Protocol("gap", ("jp", "j", "wmap", "p", "k", "pb", "ps", "Rs"),
             ("e", "n", "d_s", "n_s", "h", "slope", "worn", "c_eff", "delta"),
             "the gap geometry of contact k of joint j with the ball's point pb and the "
             "socket's point ps (global) in a socket of rotation Rs: the distance e along "
             "the outward normal n (global), the offset d_s and the normal n_s in the socket "
             "frame, the wear depth h under the contact [m], its gradient ``slope`` with "
             "respect to pb, whether the coating is worn through there, the local clearance "
             "c_eff = c + h [m] and the penetration delta (negative: a gap) [m]"),
    Protocol("contact", ("j", "model", "ball", "socket", "full", "dg"),
             ("force", "moment_ball", "moment_socket", "diss_power"),
             "the socket's action on the ball of joint j (``ball``, ``socket``: each body's "
             "(r, v, R, w) and the joint's point on it, a body offset): the force on the "
             "ball's body [N, global], its moment about that body's centroid [N m, the "
             "body's frame], the opposite force's moment on the socket's body [N m, its "
             "frame] and the power dissipated by damping and friction [W]; with ``full`` (a "
             "step's end) the joint's diagnostics into dg"),
    Protocol("elastic_law", ("p", "j"), ("law",),
             "the elastic law of joint j's one-point contact force (``contact.respond``'s "
             "``law``: 0 the paper's, n > 0 the power law F_el = A c (delta / c)^n), which "
             "its ``contact`` takes and the step's stiff rate reads (``force_rate``) "
             "from the case's parameters p: the case's (``contact.elastic``) for a ball, a "
             "journal's own where the case keeps the paper's; a type whose force is not a "
             "one-point law (the guide's lines, a bushing): the case's, never read"),
    Protocol("paper_angle", ("jp", "j", "pen", "e"), ("beta", "paper"),
             "a one-point contact's angle beta [rad] of the paper's slip rule at the "
             "penetration pen against the unworn radii [m] and the eccentricity e [m] "
             "(docs/physics.md 5: the wear's sliding distance R_i |beta - beta_prev|), and "
             "whether the type follows that rule; one that does not (a bearing, whose "
             "sliding distance is always the slip times the step): (pi, False)"),
    Protocol("wear_surface", ("jp", "j", "pen", "e", "n"),
             ("area", "wx", "wy", "wz", "scale"),
             "the wear surface of a one-point contact of normal n (global) at the "
             "penetration pen [m] and eccentricity e [m]: the contact area [m^2] the step's "
             "worn volume spreads over, the weights of the paper's three projections "
             "(|n| on a sphere; the bearing's axis) and the surface's scale of the waiting "
             "cap (R_i [m] on a sphere, R_i L [m^2] on a bearing); a multi-contact type "
             "(its own accept) and one that does not wear: zeros"),
    Protocol("cap_mergeable", ("j", "d2", "tol", "area", "scale"), ("mergeable",),
             "whether joint j's wear of a step, its mean direction a squared distance d2 from the "
             "waiting cap's (both unit), may join that cap of area ``area`` [m^2] on a "
             "surface of scale ``scale`` (``wear_surface``'s) without moving it by more than "
             "the fraction tol of its angular radius; a type without caps: False"),
    Protocol("deposit_cap", ("wmap", "j", "n", "vol", "area", "scale", "scratch"), ("top",),
             "spread the waiting cap of joint j (direction n, volume vol [m^3], mean area "
             "[m^2], the surface's scale) on its map (``scratch``: a work array of "
             "4 npolar x 3) and return the largest depth written [m]; a type without "
             "caps: 0"),
    Protocol("accept", ("j", "model", "body", "hs", "in_settled", "stats", "cur"),
             ("changed",),
             "a multi-contact joint's accepted (sub-)step of length hs, the ball's body at "
             "the state ``body`` (r, v, R, w): its contact points' episodes, the joint's "
             "impacts into stats (``in_settled``: the settled window's too) and its wear of "
             "the step into ``cur``; whether an episode changed (the step-end evaluation "
             "is redone). A one-point type's step is the kernel's one-point rule "
             "(``rk4.accept_substep``): False"),
    Protocol("deposit_step", ("wmap", "j", "jp", "cur", "wvol"), ("top",),
             "spread a multi-contact joint's accepted step wear (``cur``, from ``accept``) "
             "on its map, add its volume to wvol[j], clear it, and return the largest depth "
             "written [m]; a one-point type (its caps wait: ``deposit_cap``): 0"),
    Protocol("penetration", ("j", "model", "k", "body"), ("delta",),
             "the penetration [m] of contact k of a multi-contact joint with the ball's "
             "body at the state ``body`` (r, v, R, w), where the diagnostics hold the "
             "deepest contact's alone (the adaptive step's onset location); a one-point "
             "type, whose diagnostics hold its one contact's: -inf"),
    Protocol("section_offsets", ("jp", "j", "d", "rate"), ("offset", "offset_rate"),
             "the Poincare section's offset of the ball's point in the socket's frame d [m] "
             "and its rate [m/s] each over the clearance of its direction (the section's "
             "offset and rate, 3-vectors; a free direction 0: the block's position along its "
             "guide); a type without clearance: NaN"),
    Protocol("seat", ("j", "model", "dg", "body"), ("seated",),
             "a case's first evaluation found joint j with clearance in contact (a seated "
             "start: dg the diagnostics, ``body`` the ball's body state (r, v, R, w)): its "
             "contact episode begins without an impact (its state in model.s); whether the "
             "start must be evaluated again. A type that never touches: False"),
    Protocol("rate_point", ("j", "model", "dg"),
             ("due", "mobile", "offset_ball", "offset_socket"),
             "where joint j's force acts for its stiff rate at a step's end (dg: that "
             "evaluation's diagnostics; docs/physics.md section 4): whether a rate is due "
             "(a one-point contact: in contact or closing within one output step; a "
             "bushing: always), whether it is rated on the mobility of the joint's points "
             "(False: the type rates its force on its own, as the guide's corners do), and "
             "the points' offsets from the ball's and the socket's centres [m, global] (a "
             "contact's: its radii along the normal; zero: the centres themselves)"),
    Protocol("force_rate", ("j", "model", "dg", "wp", "y", "law"), ("rate",),
             "the largest stiff rate [1/s] of joint j's force at a step's end (docs/physics."
             "md section 4), on the mobility wp of the points ``rate_point`` names (packed "
             "symmetric 3x3 [1/kg], every constraint in place; zeros where it names none), "
             "the state y (where a type reads a body's orientation: a bushing's axis is its "
             "socket body's local x axis) and the joint's elastic law ``law`` (its "
             "``elastic_law``): a one-point "
             "contact's elastic, damping and friction rates; a bushing's spring and damper; "
             "the guide's, its corners' own (stored by its ``contact``)"),
)

#: What a joint-type module provides, compiled in that module: the names of
#: :data:`PROTOCOL`; besides these, its module's ``CONTACTS`` (how many contact points
#: the joint has: 1 for a ball or a journal, the guide's 16 corner-wall slots, 0 for a type
#: that never touches), which decides whether the kernel's one-point rules or the type's
#: own ``accept`` and ``deposit_step`` take its steps.
PROVIDES = tuple(f.name for f in PROTOCOL)
