"""The mechanism's joints as a table, and the registered joint types (docs/architecture.md,
"The joint table").

Plain data, read when the kernel is imported: the number of joints :data:`N_JOINTS` sizes
the per-joint blocks of ``layout`` (``D_*``, ``M_*``), the per-joint work arrays and the
per-joint loops of ``rk4`` and ``dopri5``; each joint's clearance parameters are its row
of the packed ``jp`` (``layout.J_*``), in the table's order. A joint type is one module of
``core/`` that declares ``JOINT_TYPE`` and provides :data:`PROVIDES`; it is registered in
:data:`JOINT_TYPES` (tests/test_joints.py fails for a module that is not, or a
registration without its module or docs).

What the table does not drive yet: ``dynamics.evaluate`` applies joint A (crank pin in
the rod), joint B (rod end in the slider), joint O (crank journal in the ground's
bearing) and joint P (the slider's block in the ground's guide) by name, with the
attachment points written there as in :data:`JOINTS`, and removes the crank's rotation
and the slider's guide analytically (ten free coordinates, the crank's two in the bearing
plane counting only where O has clearance, the slider's two across its guide only where
P has,
``dynamics.minv_apply``); tests/test_joints.py checks the table's attachments against the
packed initial state.
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

#: Each joint's row by name (``INDEX["O"]``: the revolute joint's row of jp, s, the maps).
INDEX = {joint.name: i for i, joint in enumerate(JOINTS)}

#: Registered joint types: type name -> the module of ``clearsweep.core`` that implements
#: it (that module's ``JOINT_TYPE`` is the name).
JOINT_TYPES = {"spherical": "spherical", "revolute": "revolute", "prismatic": "prismatic",
               "bushing": "bushing"}

#: What a joint-type module provides, compiled in that module (docs/architecture.md,
#: "Joint types"): the gap geometry and the contact composed into a
#: ``contact.ContactState`` (by ``contact.respond``, shared by every type); besides these,
#: its module's ``WEAR_SURFACE`` names the compiled functions its wear step reads (a
#: socket's or bearing's contact angle and area; the guide's track width and deposit).
PROVIDES = ("gap", "contact")
