"""Named indices of the kernel's flat vectors, and status codes.

Plain integers: Numba folds them into the compiled code as constants. Per-joint blocks
(one value, or 3, per joint, joint-major) are N_JOINTS long: the joint table
(``joints.JOINTS``) sets how many.
"""

from .joints import N_JOINTS

# --- global parameter vector p (float64) -----------------------------------
P_L2 = 0            # crank length l2 [m]
P_L3 = 1            # rod length l3 [m]
P_ZS = 2            # slider guide height z_s [m]
P_M2 = 3            # crank mass [kg]
P_M3 = 4            # rod mass [kg]
P_M4 = 5            # slider mass [kg]
P_J2 = 6            # crank principal inertia, 3 values [kg m^2]
P_J3 = 9            # rod principal inertia, 3 values [kg m^2]
P_J4 = 12           # slider principal inertia, 3 values [kg m^2]
P_G = 15            # gravity vector, 3 values [m/s^2]
P_OMEGA = 18        # crank speed [rad/s]
P_THETA0 = 19       # initial crank angle [rad]
P_BAUM_A = 20       # Baumgarte alpha [1/s]
P_BAUM_B = 21       # Baumgarte beta [1/s]
P_CR = 22           # restitution coefficient [-]
P_DV0_MIN = 23      # floor of the impact velocity [m/s]
P_FRICTION = 24     # 1.0 = friction on
P_V0 = 25           # friction ramp start [m/s]
P_V1 = 26           # friction ramp end [m/s]
P_WEAR = 27         # 1.0 = wear on
P_SLIP = 28         # 0.0 sliding |v_t| dt, 1.0 paper R_i |d beta|
P_AMPL = 29         # wear amplification [-]
P_PEN_FRAC = 30     # contact.max_penetration_fraction [-]; 0: the physical stop (J_PEN_STOP)
P_CONS_TOL = 31     # constraint violation stop [m]
P_ENERGY_TOL = 32   # energy residual stop, fraction of the throughput [-]
P_STAB = 33         # largest accepted rate * h [-]
P_DT = 34           # output-grid step h [s]
P_MAX_LEVEL = 35    # largest sub-step level k (2**k sub-steps)
P_SETTLE = 36       # start of the settled statistics window [s]
P_FEEDBACK = 37     # 1.0 = the worn depth enlarges the local clearance c_eff
P_INTERP = 38       # 1.0 = c_eff reads the map bilinearly between bin centres, 0.0 = its bin
# adaptive Dormand-Prince 5(4) only (solver.method = dopri5)
P_RTOL = 39         # relative tolerance [-]
P_ATOL_Q = 40       # absolute tolerance of positions and angles [m | rad]
P_ATOL_V = 41       # absolute tolerance of velocities [m/s | rad/s]
P_ATOL_E = 42       # absolute tolerance of the energy integrals [J]
P_HMAX = 43         # longest step [s]
P_ONSET_TOL = 44    # longest step over which a contact begins [s]
# contact laws (docs/physics.md section 3.2): the damping law's hysteresis factor
# chi_N delta_dot0 / k_N = P_HYST_NUM / P_HYST_DEN, packed as a fraction so that the paper's
# law keeps the rounding of 20 (1 - c_r) / (13 c_r delta_dot0)
P_HYST_NUM = 45     # numerator of the hysteresis factor [-]
P_HYST_DEN = 46     # denominator of the hysteresis factor [-]
P_ONSET = 47        # 1.0 = delta_dot0 is the episode's onset value, 0.0 its running maximum
P_EXPONENT = 48     # 0.0 = the paper's elastic law; n > 0: the power law F = K delta^n
P_SECTION_PHASE = 49  # crank angle of the Poincare sections, once per revolution [rad]
P_GUIDE = 50        # the slider guide's global axis: 0.0 x (the RSSP), 1.0 y (the slider-crank)
# p[51]: unused, 0: an even length keeps a device thread's copy of p 16-byte aligned (its
# paired local loads: at 51 values the A,B build's spill stores rose 992 -> 1,000 B;
# python -m clearsweep.ptx --joints A,B)
N_P = 52

# --- per-joint parameters jp[j, :] (j: the joint's row of joints.JOINTS) ------
# Each column has one meaning whatever the joint's type; a type that has no use for a column
# leaves it 0 (docs/architecture.md, "Packed columns").
J_CLEARANCE = 0     # 1.0 = clearance joint, 0.0 = ideal
J_C = 1             # the joint's clearance c [m]: its least gap (radial c of a ball or a
                    # journal; the smaller of a guide's c_y and c_z)
J_RI = 2            # socket (bearing) radius R_i [m]; point contacts only
J_RJ = 3            # ball (journal) radius R_j [m]; point contacts only
J_EW = 4            # modulus of the joint's elastic law [Pa]: Hertz's E* (power law), else E_w
J_MU = 5            # friction coefficient of the socket surface [-]
J_K = 6             # wear coefficient of the socket surface [m^2/N]
# base material, used where the bin of the contact direction is worn to J_COAT or deeper
J_EW_BASE = 7       # J_EW of the uncoated pair [Pa]
J_MU_BASE = 8       # friction coefficient of the base [-]
J_K_BASE = 9        # wear coefficient of the base [m^2/N]
J_COAT = 10         # coating thickness [m]; inf = no coating to wear through
J_LENGTH = 11       # bearing length L [m] (revolute joints); else 0
# a prismatic joint's block in its guide (0 for the other types)
J_WIDTH = 12        # block width, across the guide along y [m]
J_HEIGHT = 13       # block height, across the guide along z [m]
J_CY = 14           # clearance between the block's sides and the guide's y walls [m]
J_CZ = 15           # clearance between the block's top / bottom and the guide's z walls [m]
J_X0 = 16           # start of the walls' wear maps along the guide (x) [m]
J_XSPAN = 17        # length of the walls' wear maps along the guide [m]
J_PEN_STOP = 18     # penetration stop [m] (docs/physics.md 4.3)
J_FILM = 19         # lubricant film's viscous coefficient [N s/m] along the slip (O: Petroff); else 0
J_BLOCK_LENGTH = 20  # block length 2a along the guide [m] (prismatic joints); else 0
J_CORNER_RADIUS = 21  # radius r_c of the block's rounded edges [m] (prismatic joints); else 0
# an elastic bushing (core/bushing.py; 0 for the other types): the joint's coordinates are
# free as a clearance joint's, its J_CLEARANCE 0 (no gap, no contact, no wear)
J_BUSHING = 22      # 1.0 = the joint is an elastic bushing
J_K_RADIAL = 23     # bushing stiffness across its axis [N/m]
J_K_AXIAL = 24      # bushing stiffness along its axis [N/m] (0 at a revolute's place: axial ideal)
J_C_RADIAL = 25     # bushing damping across its axis [N s/m]
J_C_AXIAL = 26      # bushing damping along its axis [N s/m]
N_JP = 27

# --- state vector y ---------------------------------------------------------
# q = [r2, phi2, r3, phi3, r4, phi4] (18), then qd (18), then two integrals.
# r: body origin, 3 values [m]; phi: Euler angles (alpha, beta, gamma) [rad]. The
# velocity of coordinate Y_x is at Y_QD + Y_x.
Y_R2 = 0            # crank centre of mass, 3
Y_PHI2 = 3          # crank angles, 3
Y_R3 = 6            # rod centre of mass, 3
Y_PHI3 = 9          # rod angles, 3
Y_R4 = 12           # slider centre of mass, 3
Y_PHI4 = 15         # slider angles, 3
Y_CRANK_ANGLE = Y_PHI2 + 2   # gamma2, the crank rotation theta [rad]
Y_ROD_BETA = Y_PHI3 + 1      # beta3, the rod's Euler angle that must stay off +-90 deg
Y_SLIDER_X = Y_R4            # slider position along the RSSP's guide (x) [m]; the slider-crank's
                             # runs along y: Y_R4 + jointset.guide_axis (host: guide_slot)
N_Q = 18
Y_QD = 18
Y_WORK = 36         # work done by the drive [J]
Y_DISS = 37         # energy dissipated by contact damping and friction [J]
N_Y = 38

# --- discrete contact state s[j, :] (one row per joint) -----------------------------------------
S_DV0 = 0           # impact velocity of the current contact, 0 = none [m/s]
S_BETA = 1          # contact angle beta at the last accepted step [rad]
# a prismatic joint: each corner-wall pair's impact velocity (prismatic.SLOTS of them:
# 8 corners, each against the y wall and the z wall it faces), 0 = not in contact [m/s]
S_SLOT = 2
P_SLOTS = 16
# a one-point joint (ball, journal) keeps in its slots the wear-map bin its contact last read
# and that bin's edges less a margin (wear.map_bin_near; a journal's bearing map the azimuth
# columns alone, wear.angle_bin_near): a hint, never a result (all zero: none). The polar
# and azimuth bins; the polar edges' cosines; the azimuth edges' directions.
S_HINT_IP = S_SLOT
S_HINT_IA = S_SLOT + 1
S_HINT_CZ_LO = S_SLOT + 2      # the bin holds cos(theta) above this ...
S_HINT_CZ_HI = S_SLOT + 3      # ... and below this
S_HINT_EDGE = S_SLOT + 4       # (x, y) of the azimuth bin's first edge, then of its second
N_S = S_SLOT + P_SLOTS

# --- the wear of a step on its way to the map, cur[j, :] and pend[j, :] (rk4.merge_wear) ---
# a spherical or revolute joint's row j: sum V n (3), sum V, sum V A, the surface's scale; a
# prismatic joint's row j: sum V in column 0; its corner-wall pair k: sum V / w, sum (V / w)
# x, sum (V / w) a (w the track's width, x along the guide, a across the wall) in row
# CAP_SLOT_ROW + k // 2, columns 3 (k % 2) .. 3 (k % 2) + 2: rows of 6, as the other
# joints' wear has them
N_CAP = 6
CAP_SLOT_ROW = N_JOINTS
N_CAP_ROWS = N_JOINTS + P_SLOTS // 2

# --- diagnostics vector d (one evaluation of the right-hand side) ----------
D_SLIDER_ACC = 0
D_TORQUE = 1
D_REACTION_O = 2    # 3 values
D_JOINT_FORCE = 5   # N_JOINTS x 3 values, joint-major
D_FN = D_JOINT_FORCE + 3 * N_JOINTS     # per joint
D_FT = D_FN + N_JOINTS                  # per joint
D_DELTA = D_FT + N_JOINTS               # per joint
D_ECC = D_DELTA + N_JOINTS              # per joint
D_OFFSET = D_ECC + N_JOINTS             # N_JOINTS x 3, ball-centre offset in the socket frame
D_NORMAL = D_OFFSET + 3 * N_JOINTS      # N_JOINTS x 3, contact normal in the socket frame
D_DDOT = D_NORMAL + 3 * N_JOINTS        # per joint, normal approach rate
D_VT = D_DDOT + N_JOINTS                # per joint, tangential slip speed
D_CEFF = D_VT + N_JOINTS                # per joint, local clearance c_eff
D_HWEAR = D_CEFF + N_JOINTS             # per joint, wear depth under the contact point
D_UEL = D_HWEAR + N_JOINTS              # per joint, contact elastic energy
D_RATE = D_UEL + N_JOINTS               # largest stiff rate of the system [1/s]
D_KE = D_RATE + 1
D_PE_GRAV = D_KE + 1
D_CONS = D_PE_GRAV + 1                  # largest position-constraint violation [m]
D_PDRIVE = D_CONS + 1
D_PDISS = D_PDRIVE + 1
D_NGLOBAL = D_PDISS + 1                 # N_JOINTS x 3, contact normal in the global frame
D_DFD = D_NGLOBAL + 3 * N_JOINTS        # per joint, dF_N/d delta [N/m]
D_DFDD = D_DFD + N_JOINTS               # per joint, dF_N/d delta_dot [N s/m]
D_WORN = D_DFDD + N_JOINTS              # per joint, 1.0 = coating worn through under the
                                        # contact point (base values used)
D_PRATE = D_WORN + N_JOINTS             # largest stiff rate of a prismatic joint's corners [1/s]
N_D = D_PRATE + 1

# --- running statistics m[w, :] (w = 0: whole run, 1: settled window) ---------
# Updated at every accepted RK4 (sub-)step end, never from the saved output rows.
W_WHOLE = 0
W_SETTLED = 1
N_WINDOWS = 2
M_FN_PEAK = 0                       # per joint, peak normal force [N]
M_PEN_PEAK = M_FN_PEAK + N_JOINTS   # per joint, peak penetration [m]
M_IMPACTS = M_PEN_PEAK + N_JOINTS   # per joint, contact episodes begun (impacts) [-]
M_VIMP_MAX = M_IMPACTS + N_JOINTS   # per joint, largest approach velocity at an impact [m/s]
M_CONTACT_T = M_VIMP_MAX + N_JOINTS  # per joint, time in contact [s]
M_ACC_PEAK = M_CONTACT_T + N_JOINTS  # peak |slider acceleration| [m/s^2]
M_ACC_SQ = M_ACC_PEAK + 1           # integral of slider acceleration^2 dt [m^2/s^3]
M_TORQUE_PEAK = M_ACC_SQ + 1        # peak |crank torque| [N m]
M_TIME = M_TORQUE_PEAK + 1          # duration the window covers [s]
M_SAMPLES = M_TIME + 1              # step-end samples in the window [-]
N_M = M_SAMPLES + 1

# --- Poincare sections sec[k, :] (one row per crank revolution k; rk4.section_time) ----
# Read within the (sub-)step holding the section time, at that time exactly; NaN where not
# taken (an ideal joint's offsets, a run that stopped before).
SEC_TIME = 0                            # time of the section [s]
SEC_SLIDER_ACC = 1                      # slider acceleration [m/s^2]
SEC_OFFSET = 2                          # N_JOINTS x 3: D_OFFSET / c (socket frame) [-]
SEC_RATE = SEC_OFFSET + 3 * N_JOINTS    # N_JOINTS x 3: its rate / c [1/s]
N_SEC = SEC_RATE + 3 * N_JOINTS

# --- counters info[:] (int64) of one run ------------------------------------
I_STATUS = 0        # status code (ST_*)
I_SAVED = 1         # output rows saved (or that a run keeping rows would save)
I_DEEPEST = 2       # deepest sub-step level k taken (dopri5: of the shortest step)
I_SUBSTEPS = 3      # RK4 sub-steps taken (dopri5: accepted steps)
I_STEPS = 4         # output-grid steps completed, the stopping step included
I_SECTIONS = 5      # Poincare sections taken (rows of Out.sec written)
N_INFO = 6

# --- energy tracking track[:] (float64) of one run ----------------------------
T_KE_PEAK = 0       # peak kinetic energy [J]
T_WORK_MAX = 1      # largest |drive work| [J]
T_RESIDUAL_MAX = 2  # largest |energy residual| [J]
N_TRACK = 3

# --- what an integrator returns, r[:] (float64; kernel_result) ---------------
R_RESIDUAL_MAX = 0  # largest |energy residual| [J]
R_KE_PEAK = 1       # peak kinetic energy [J]
R_FIRST_IMPACT = 2  # per joint, first impact time [s], NaN where none
N_R = R_FIRST_IMPACT + N_JOINTS

# --- status codes -----------------------------------------------------------
ST_OK = 0
ST_UNSTABLE_STEP = 1
ST_PENETRATION = 2
ST_CONSTRAINT = 3
ST_ENERGY = 4
ST_NONFINITE = 5
ST_EULER = 6
ST_SINGULAR = 7

STATUS_NAMES = {
    ST_OK: "ok",
    ST_UNSTABLE_STEP: "unstable_step",
    ST_PENETRATION: "penetration_exceeded",
    ST_CONSTRAINT: "constraint_violation",
    ST_ENERGY: "energy_residual",
    ST_NONFINITE: "non_finite",
    ST_EULER: "euler_singularity",
    ST_SINGULAR: "singular_constraints",
}

N_ANGLE_BINS = 360  # one-degree projection bins (docs/physics.md section 5)
