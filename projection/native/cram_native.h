/* cram_native.h -- the C interface of libcram_native.
 *
 * A physics belief state for mobile manipulation: Bullet worlds (double precision), URDF
 * articulated objects, contact / distance / ray queries, attachments, headless rendering with
 * visibility queries, and KDL inverse kinematics.
 *
 * Conventions
 *   - Every function returns an int: a status (0 = ok, negative = CN_E_* error code) or a
 *     handle / count >= 0.  On a negative result, cn_last_error() gives a text naming the bad
 *     value.  The error text is per thread.  No C++ exception escapes.
 *   - Lengths in metres, angles in radians (fov in degrees), poses as 7 doubles
 *     x y z qx qy qz qw (quaternions are normalised on the way in).
 *   - Handles are ints.  World and IK-chain handles are global; object handles (bodies and
 *     articulated objects share one numbering) belong to one world.  A copy of a world keeps
 *     every object handle.  Removed or destroyed handles are never valid again.  Link and
 *     joint indices are per articulated object, 0 .. count-1.
 *   - "link" arguments of the object-level queries are -1 for a plain body or for "the whole
 *     articulated object".
 *   - Out arrays are caller-owned.  Functions filling a variable number of records take a
 *     capacity (in records) and return the total number available; at most `cap` are written.
 *   - Calls may come from any thread: every entry point runs under one process-wide lock.
 *   - The caller's floating point environment is kept: a call that computes masks every
 *     exception while it runs and restores the caller's control word, so a host that traps
 *     (SBCL: invalid, overflow, division by zero) never sees a trap from inside the library.
 *     Teleporting a body that carries no attachment to a pose of moderate magnitudes only
 *     normalises and copies, and skips that masking.
 *   - Moving bodies (teleports, joint values) leaves their broadphase bounding boxes to be
 *     brought up to date once, at the next contact, ray or physics call.
 */
#ifndef CRAM_NATIVE_H
#define CRAM_NATIVE_H

#ifdef __cplusplus
extern "C" {
#endif

/* ---- status codes -------------------------------------------------------------------- */
#define CN_OK          0
#define CN_E_HANDLE   -1   /* stale, foreign or out-of-range handle or index          */
#define CN_E_ARG      -2   /* NaN / inf / negative size / null pointer / bad option    */
#define CN_E_NAME     -3   /* unknown link, joint, package or robot name               */
#define CN_E_FILE     -4   /* missing, unreadable or corrupt file                      */
#define CN_E_PARSE    -5   /* malformed URDF                                           */
#define CN_E_STATE    -6   /* operation not possible in this state (e.g. attach cycle)  */
#define CN_E_RENDER   -7   /* OSMesa / PNG failure                                     */
#define CN_E_INTERNAL -8   /* unexpected library failure (out of memory, ...)           */

/* object kinds */
#define CN_BODY        0
#define CN_ARTICULATED 1
/* joint types */
#define CN_JOINT_FIXED      0
#define CN_JOINT_REVOLUTE   1
#define CN_JOINT_CONTINUOUS 2
#define CN_JOINT_PRISMATIC  3
#define CN_JOINT_FLOATING   4   /* kept at its origin (treated as fixed) */
#define CN_JOINT_PLANAR     5   /* kept at its origin (treated as fixed) */
/* camera conventions: optical = z forward, x right, y down (ROS *_optical_frame);
 * forward = x forward, y left, z up (ROS body / link frames) */
#define CN_CAMERA_OPTICAL 0
#define CN_CAMERA_FORWARD 1

/* ---- errors and search paths ----------------------------------------------------------- */
const char *cn_last_error(void);          /* text of this thread's last error ("" if none) */
int cn_last_error_code(void);
int cn_version(void);                     /* 10000*major + 100*minor + patch                */
int cn_add_package_path(const char *package_name, const char *dir);  /* package://NAME/... */
int cn_add_search_dir(const char *dir);   /* dir containing package directories           */
int cn_clear_search_paths(void);
/* Resolve package://, file:// or plain paths (relative ones against `base_dir`, may be NULL)
 * to an existing file; writes a NUL-terminated path into out[cap]; returns its length. */
int cn_resolve_path(const char *uri, const char *base_dir, char *out, int cap);

/* ---- worlds ------------------------------------------------------------------------------ */
int cn_world_create(double gx, double gy, double gz);      /* -> world handle             */
int cn_world_destroy(int world);
int cn_world_copy(int world);       /* -> new world: same objects, handles, poses, velocities,
                                       joint states, attachments, filters; shapes shared   */
int cn_world_alive(int world);      /* 1 live, 0 not (never an error)                      */
int cn_world_count(void);           /* number of live worlds                               */
int cn_world_set_gravity(int world, double gx, double gy, double gz);
int cn_world_get_gravity(int world, double *out3);
int cn_world_step(int world, double dt);                   /* one stepSimulation(dt)       */
/* ceil(seconds/dt) steps -> n; stops early once every dynamic body sleeps or has moved slower
 * than 1 mm/s and 0.01 rad/s for 0.1 s: the remaining steps would leave it where it is. */
int cn_world_simulate(int world, double seconds, double dt);
int cn_world_num_objects(int world);                        /* live objects                */
int cn_world_num_bodies(int world);  /* rigid bodies in Bullet (plain bodies + link bodies) */
int cn_world_objects(int world, int *out, int cap);          /* live object handles -> count */

/* ---- objects (bodies and articulated objects) --------------------------------------------- */
int cn_object_kind(int world, int obj);                      /* CN_BODY / CN_ARTICULATED   */
int cn_object_remove(int world, int obj);                    /* also drops its attachments */
int cn_object_get_pose(int world, int obj, double *out7);    /* body pose / base pose      */
int cn_object_set_pose(int world, int obj, const double *pose7); /* teleport, reactivates;
                                                 rigidly attached objects follow         */
int cn_object_get_poses(int world, const int *objs, int n, double *out7n);
int cn_object_set_poses(int world, const int *objs, int n, const double *poses7n);
int cn_object_set_color(int world, int obj, int link, double r, double g, double b, double a);
int cn_object_get_color(int world, int obj, int link, double *out4);
int cn_robot_link_colors(int world, int robot, double *out4, int cap); /* every link's colour as
                                   cn_object_get_color gives it, 4 per link -> num links */
int cn_object_set_collision_filter(int world, int obj, int group, int mask);
int cn_object_get_collision_filter(int world, int obj, int *out2);
int cn_object_aabb(int world, int obj, int link, double *out6);  /* min xyz, max xyz    */
int cn_object_local_aabb(int world, int obj, int link, double *out6); /* the same box in the
                                                 object's (or link's) own frame            */
int cn_robot_link_aabbs(int world, int robot, double *out6, int cap); /* every link's box as
                                   cn_object_aabb gives it, 6 per link -> num links          */
int cn_object_is_active(int world, int obj);                 /* 1 if any body is awake     */

/* ---- rigid bodies (mass 0 = static) -------------------------------------------------------- */
int cn_body_add_plane(int world, double nx, double ny, double nz, double constant);
int cn_body_add_box(int world, const double *pose7, double sx, double sy, double sz,
                    double mass);                  /* FULL extents sx, sy, sz              */
int cn_body_add_sphere(int world, const double *pose7, double radius, double mass);
int cn_body_add_cylinder(int world, const double *pose7, double radius, double height,
                         double mass);             /* axis = local z                      */
int cn_body_add_cone(int world, const double *pose7, double radius, double height,
                     double mass);                 /* axis = local z, apex at +height/2    */
/* STL / OBJ / DAE through assimp.  Sub-meshes are the meshes of the file as assimp reads
 * them (an OBJ object or group, a DAE geometry; an STL file has one), never joined.  Movable
 * bodies: one convex hull per sub-mesh, children of a compound shape (a sub-mesh of more than
 * 64 triangle corners: the hull of its support points in 42-odd fixed directions); static
 * bodies (mass 0): the exact triangle mesh.  flags: CN_MESH_SINGLE_HULL = the exact convex
 * hull of every vertex of every sub-mesh instead, movable or static (concavities between the
 * parts are filled).  cn_body_add_mesh = flags 0.  Loaded shapes are cached by path + scale +
 * kind of shape. */
#define CN_MESH_SINGLE_HULL 1
int cn_body_add_mesh(int world, const double *pose7, const char *path,
                     double sx, double sy, double sz, double mass);
int cn_body_add_mesh_flags(int world, const double *pose7, const char *path,
                           double sx, double sy, double sz, double mass, int flags);
int cn_body_add_convex_hull(int world, const double *pose7, const double *points3n, int n,
                            double mass);
int cn_body_get_velocity(int world, int body, double *out6);        /* linear, angular     */
int cn_body_set_velocity(int world, int body, const double *vel6);
int cn_body_get_mass(int world, int body, double *out1);
/* shape description: kind (0 plane, 1 box, 2 sphere, 3 cylinder, 4 cone, 5 mesh, 6 hull),
 * dims: box sx sy sz / sphere r / cylinder & cone r h / plane nx ny nz c / mesh sx sy sz */
int cn_body_shape(int world, int body, double *out_dims4);          /* -> kind             */

/* ---- articulated objects from URDF ---------------------------------------------------------- */
/* One kinematic rigid body per link with collision geometry.  flags: CN_URDF_EXACT_MESHES =
 * collision meshes as exact triangle meshes (for static environments); CN_URDF_SINGLE_HULL =
 * each collision mesh as the exact convex hull of all its vertices; neither: one convex hull per
 * sub-mesh of each collision mesh (as cn_body_add_mesh).  The two flags exclude each other.
 * Every joint starts at 0. */
#define CN_URDF_EXACT_MESHES 1
#define CN_URDF_SINGLE_HULL  2
int cn_robot_add_urdf(int world, const char *urdf_xml, const double *base_pose7, int flags);
/* The same with the origins of the n joints joint_names[i] set to the <origin> attribute texts
 * xyz[i] and rpy[i], read as the URDF parser reads them: what cn_robot_add_urdf gives for the
 * text with those <origin> elements changed, without parsing it (the model of urdf_xml is
 * parsed once and shared). */
int cn_robot_add_urdf_moved(int world, const char *urdf_xml, const double *base_pose7, int flags,
                            int n, const char *const *joint_names, const char *const *xyz,
                            const char *const *rpy);
int cn_robot_name(int world, int robot, const char **out_name);
int cn_robot_num_links(int world, int robot);
int cn_robot_num_joints(int world, int robot);     /* all joints, fixed ones included     */
int cn_robot_root_link(int world, int robot);
int cn_robot_link_name(int world, int robot, int link, const char **out_name);
int cn_robot_joint_name(int world, int robot, int joint, const char **out_name);
int cn_robot_link_index(int world, int robot, const char *name);
int cn_robot_joint_index(int world, int robot, const char *name);
/* ints: type, parent link, child link, mimicked joint (-1);
 * doubles: lower, upper, max velocity, max effort, axis x y z, mimic multiplier, offset */
int cn_robot_joint_info(int world, int robot, int joint, int *out4, double *out9);
int cn_robot_link_parent_joint(int world, int robot, int link);     /* -> joint or -1     */
int cn_robot_link_has_body(int world, int robot, int link);         /* 1 if it collides   */
/* Set n joints at once (fixed / floating / planar joints ignore the value; mimic joints
 * always follow their leader), then forward kinematics and attached objects, once. */
int cn_robot_set_joints(int world, int robot, const int *joints, const double *values, int n);
int cn_robot_get_joints(int world, int robot, double *out, int cap);     /* -> num joints */
int cn_robot_get_joint(int world, int robot, int joint, double *out);  /* one joint's value */
int cn_robot_link_poses(int world, int robot, double *out7, int cap);    /* -> num links  */
int cn_robot_link_pose(int world, int robot, int link, double *out7);
/* The poses of the nl links LINKS the robot's links would have with its nj joints JOINTS at
 * VALUES (mimic joints following), its other joints and its base as they are: the poses
 * cn_robot_set_joints and cn_robot_link_pose would give, computed the same way; nothing in the
 * world changes. 7 doubles per link into out7. */
int cn_robot_link_poses_if(int world, int robot, const int *joints, const double *values, int nj,
                           const int *links, int nl, double *out7);
int cn_robot_set_self_collision(int world, int robot, int enabled);      /* default off   */

/* ---- collision queries ------------------------------------------------------------------- */
/* Pairs in contact: closest distance <= threshold (0 = touching or penetrating).  Records:
 * ints (objA, linkA, objB, linkB), doubles (min distance). -> number of pairs */
int cn_world_contacts(int world, double threshold, int *out4, double *out_dist, int cap);
int cn_object_contacts(int world, int obj, double threshold, int *out4, double *out_dist,
                       int cap);                     /* obj (all its links) against others */
/* The same, leaving out the contacts with the n_except objects of except (their handles). */
int cn_object_contacts_except(int world, int obj, double threshold, const int *except,
                              int n_except, int *out4, double *out_dist, int cap);
/* The first contact of the articulated obj's links (with other objects, and with each other
 * when its self-collision is on) that is not left out, as (obj, link, other, other_link) in
 * out4. Left out: the objects of except, the n_skip links of obj in skip_links, and the
 * n_allowed (link, other, other_link) triples of allowed3 (-2 for any). Returns 1 when there
 * is such a contact, 0 when there is none: a yes/no collision check that stops at the first. */
int cn_object_first_contact(int world, int obj, double threshold, const int *except, int n_except,
                            const int *skip_links, int n_skip, const int *allowed3, int n_allowed,
                            int *out4);
/* Whether the contact queries of an articulated object's links (cn_object_contacts*,
 * cn_object_first_contact) leave out the pairs a GJK distance (a lower bound) proves more than
 * threshold + 1 mm apart, without asking Bullet: on (1) by default; off (0) for comparisons.
 * The answers are the same either way. -> the setting before. */
int cn_set_contact_prefilter(int on);
/* Closest distance between two objects (link -1 = whole object), searched up to max_dist.
 * out7: distance, point on A xyz, point on B xyz.  Returns 1 if a pair closer than max_dist
 * was found, 0 if not (distance then = max_dist). */
int cn_closest_distance(int world, int objA, int linkA, int objB, int linkB, double max_dist,
                        double *out7);
/* Exclude a pair from contacts and physics (link -1 = whole object); ignore = 1 adds, 0 drops */
int cn_ignore_pair(int world, int objA, int linkA, int objB, int linkB, int ignore);
/* n rays from[3n] -> to[3n].  out_hit2n: obj, link (-1 -1 = no hit);
 * out7n: fraction, point xyz, normal xyz.  -> number of hits */
int cn_ray_test(int world, const double *from3n, const double *to3n, int n,
                int *out_hit2n, double *out7n);

/* ---- sweep checks ---------------------------------------------------------------------- */
/* What a robot passes through on its way from one state to another, not only at the two:
 * its base moves on a straight line (rotation by slerp) from base_from7 to base_to7 while its
 * joints (nq = every joint, as cn_robot_get_joints) move linearly from q_from to q_to. Its
 * links and its rigidly attached objects (and theirs) are checked against every other object
 * (collision filters and ignored pairs apply); the robot itself and its current poses in the
 * world are not touched. ignore4: n_ignore records (moving obj, moving link, hit obj, hit link)
 * that are not reported, -1 = any (an object -1 needs link -1). max_step (> 0): largest summed
 * rotation (rad) and translation (m) of one sub-step; tolerance (> 0, m): a pair is reported
 * only where its computed distance is <= 0, and missed only when it never gets deeper than
 * tolerance. flags: CN_SWEEP_SKIP_START_CONTACTS leaves out pairs within tolerance at the
 * start (the move leaves from that contact).
 * Records, each pair once at its first contact, earliest first: ints (moving obj, moving link
 * (-1 for a body), hit obj, hit link); doubles (fraction of the move in [0, 1], contact point
 * x y z). -> number of pairs (at most cap written) */
#define CN_SWEEP_SKIP_START_CONTACTS 1
/* For tests: the reference search, plain and slower, which must give the same records. */
#define CN_SWEEP_REFERENCE 2
int cn_robot_sweep_check(int world, int robot, const double *base_from7, const double *q_from,
                         const double *base_to7, const double *q_to, int nq,
                         const int *ignore4, int n_ignore, double max_step, double tolerance,
                         int flags, int *out4, double *out4d, int cap);
/* The same for a body (and the bodies rigidly attached to it) moving from from7 to to7. */
int cn_body_sweep_check(int world, int body, const double *from7, const double *to7,
                        const int *ignore4, int n_ignore, double max_step, double tolerance,
                        int flags, int *out4, double *out4d, int cap);
/* Where moving frames are along the motion cn_robot_sweep_check checks (the same arguments up
 * to nq): at the steps + 1 times 0, 1/steps .. 1 (1 <= steps <= 10000), the origins of the
 * n_frames frames2 pairs (robot, link) for a link, (body, -1) for a body the robot carries
 * rigidly (a body it does not carry stays where it is). out3: n_frames * (steps + 1) * 3
 * doubles, frame by frame, x y z per time. The world is not changed. -> n_frames */
int cn_robot_sweep_paths(int world, int robot, const double *base_from7, const double *q_from,
                         const double *base_to7, const double *q_to, int nq, const int *frames2,
                         int n_frames, int steps, double *out3);

/* ---- attachments ------------------------------------------------------------------------ */
/* Attach body `obj` to `parent` (an articulated object with link >= 0, or a body with -1).
 * rigid (loose = 0): obj keeps its transform relative to the link and is made kinematic;
 * loose = 1: only recorded. */
int cn_attach(int world, int obj, int parent, int link, int loose);
int cn_detach(int world, int obj, int parent);  /* parent -1: all; -> number removed */
/* records: obj, parent, link, loose -> count */
int cn_attachments(int world, int *out4, int cap);

/* ---- rendering (OSMesa, headless) ---------------------------------------------------------- */
/* Any of rgb (3*w*h bytes), depth (w*h metres along the view axis, 0 = nothing) and
 * seg (2*w*h ints: obj, link; -1 -1 = background) may be NULL.  Rows top to bottom. */
int cn_render(int world, const double *camera7, int convention, double fov_y_deg,
              int width, int height, double near_m, double far_m,
              unsigned char *rgb, double *depth, int *seg);
int cn_render_png(int world, const double *camera7, int convention, double fov_y_deg,
                  int width, int height, const char *png_path);
int cn_write_png(const char *path, const unsigned char *rgb, int width, int height);
/* camera pose at eye looking at target, `up` roughly up */
int cn_look_at(const double *eye3, const double *target3, const double *up3, int convention,
               double *out7);
/* Visible fraction of (obj, link) (link -1 = all its links) from the camera: its pixels in
 * the scene / its pixels rendered alone with the camera turned towards it.  Occluding
 * object handles -> out_occluders[cap]; returns their number. */
int cn_visibility(int world, const double *camera7, int convention, double fov_y_deg,
                  int width, int height, int obj, int link, double *out_fraction,
                  int *out_occluders, int cap);
/* Same, counting only the parts of the object above the height min_z (world z): the part of
 * an item sunk into the board it stands on is seen by no camera.  min_z -inf: all of it. */
int cn_visibility_above(int world, const double *camera7, int convention, double fov_y_deg,
                        int width, int height, int obj, int link, double min_z,
                        double *out_fraction, int *out_occluders, int cap);

/* ---- inverse kinematics (KDL) -------------------------------------------------------------- */
int cn_chain_create(int world, int robot, const char *base_link, const char *tip_link);
int cn_chain_destroy(int chain);
int cn_chain_num_joints(int chain);
int cn_chain_joints(int chain, int *out_robot_joints);        /* robot joint indices      */
int cn_chain_limits(int chain, double *out_lower, double *out_upper);
int cn_chain_fk(int chain, const double *q, double *out7);     /* tip in base_link frame   */
/* 1 when the tip may come within pos_tol m of position3 (base_link frame), 0 when no joint
 * values within the limits bring it there (the chain's reach map, built at its first use;
 * pos_tol above 2 mm: always 1).  cn_chain_ik gives such a goal up before any step. */
int cn_chain_may_reach(int chain, const double *position3, double pos_tol);
/* The chain's reach map as numbers, to keep beyond this process (a saved Lisp core): out_params
 * gets CN_REACH_PARAMS doubles (the first two the halves of a hash of the chain's joints, limits
 * and tip), out_cells the first `cap` of its cells.  -> the number of cells (the map built
 * first when needed; 0: the chain has no map). */
#define CN_REACH_PARAMS 20
int cn_chain_reach_map_get(int chain, double *out_params, unsigned char *out_cells, int cap);
/* Give the chain the reach map of cn_chain_reach_map_get instead of building it.  -> 1 when
 * installed, 0 when it is not a map of this chain (its hash differs: nothing changes). */
int cn_chain_reach_map_set(int chain, const double *params, const unsigned char *cells, int n);
/* IK for the tip pose (in base_link frame) from seed q; random restarts within the limits
 * drawn from `rng_seed`.  -> 0 solved (within pos_tol m and rot_tol rad), 1 not solved
 * (out_q = best found).  out_err2 (may be NULL): position and rotation error. */
int cn_chain_ik(int chain, const double *target7, const double *seed_q, int max_restarts,
                double pos_tol, double rot_tol, unsigned int rng_seed, double *out_q,
                double *out_err2);
/* How many answers of cn_chain_ik the chain keeps: those its random restarts play no part in
 * (a goal out of reach, a goal solved from the seed), asked again with the same goal, seed,
 * restart count and tolerances (bit for bit); at most 4096 (emptied when full). */
int cn_chain_ik_memo_size(int chain);

#ifdef __cplusplus
}
#endif
#endif
