;;;; cram-native: worlds, objects and rigid bodies.

(in-package :cram-native)

(defcn "cn_world_create" :int (gx :double) (gy :double) (gz :double))
(defcn "cn_world_destroy" :int (w :int))
(defcn "cn_world_copy" :int (w :int))
(defcn "cn_world_alive" :int (w :int))
(defcn "cn_world_count" :int)
(defcn "cn_world_set_gravity" :int (w :int) (gx :double) (gy :double) (gz :double))
(defcn "cn_world_get_gravity" :int (w :int) (out :pointer))
(defcn "cn_world_step" :int (w :int) (dt :double))
(defcn "cn_world_simulate" :int (w :int) (s :double) (dt :double))
(defcn "cn_world_num_objects" :int (w :int))
(defcn "cn_world_num_bodies" :int (w :int))
(defcn "cn_world_objects" :int (w :int) (out :pointer) (cap :int))
(defcn "cn_object_kind" :int (w :int) (o :int))
(defcn "cn_object_remove" :int (w :int) (o :int))
(defcn "cn_object_get_pose" :int (w :int) (o :int) (out :pointer))
(defcn "cn_object_set_pose" :int (w :int) (o :int) (pose :pointer))
(defcn "cn_object_get_poses" :int (w :int) (objs :pointer) (n :int) (out :pointer))
(defcn "cn_object_set_poses" :int (w :int) (objs :pointer) (n :int) (poses :pointer))
(defcn "cn_object_set_color" :int (w :int) (o :int) (link :int)
  (r :double) (g :double) (b :double) (a :double))
(defcn "cn_object_get_color" :int (w :int) (o :int) (link :int) (out :pointer))
(defcn "cn_object_set_collision_filter" :int (w :int) (o :int) (group :int) (mask :int))
(defcn "cn_object_get_collision_filter" :int (w :int) (o :int) (out :pointer))
(defcn "cn_object_aabb" :int (w :int) (o :int) (link :int) (out :pointer))
(defcn "cn_object_local_aabb" :int (w :int) (o :int) (link :int) (out :pointer))
(defcn "cn_object_is_active" :int (w :int) (o :int))
(defcn "cn_body_add_plane" :int (w :int) (nx :double) (ny :double) (nz :double) (c :double))
(defcn "cn_body_add_box" :int (w :int) (pose :pointer) (sx :double) (sy :double) (sz :double)
  (mass :double))
(defcn "cn_body_add_sphere" :int (w :int) (pose :pointer) (r :double) (mass :double))
(defcn "cn_body_add_cylinder" :int (w :int) (pose :pointer) (r :double) (h :double) (mass :double))
(defcn "cn_body_add_cone" :int (w :int) (pose :pointer) (r :double) (h :double) (mass :double))
(defcn "cn_body_add_mesh" :int (w :int) (pose :pointer) (path :string)
  (sx :double) (sy :double) (sz :double) (mass :double))
(defcn "cn_body_add_mesh_flags" :int (w :int) (pose :pointer) (path :string)
  (sx :double) (sy :double) (sz :double) (mass :double) (flags :int))
(defcn "cn_body_add_convex_hull" :int (w :int) (pose :pointer) (pts :pointer) (n :int)
  (mass :double))
(defcn "cn_body_get_velocity" :int (w :int) (b :int) (out :pointer))
(defcn "cn_body_set_velocity" :int (w :int) (b :int) (v :pointer))
(defcn "cn_body_get_mass" :int (w :int) (b :int) (out :pointer))
(defcn "cn_body_shape" :int (w :int) (b :int) (out :pointer))

(defmacro with-out-dvec ((var n) &body body)
  "Bind VAR to a fresh DVEC of N, run BODY with VAR's pointer as VAR-PTR... and return VAR."
  `(let ((,var (make-dvec ,n)))
     (declare (type dvec ,var))
     ,@body
     ,var))

;;; ---- worlds ----------------------------------------------------------------------------

(defun make-world (&key (gravity '(0d0 0d0 -9.81d0)))
  "Create an empty physics world with GRAVITY (x y z, m/s^2); return its handle."
  (let ((g (to-dvec gravity 3 'make-world "gravity")))
    (ccall "cn_world_create" (aref g 0) (aref g 1) (aref g 2))))

(defun destroy-world (world)
  "Destroy WORLD and everything in it; its handle becomes invalid."
  (ccall "cn_world_destroy" (int-arg world 'destroy-world "world"))
  nil)

(defun copy-world (world)
  "A new world with the same objects (same handles), poses, velocities, joint states,
attachments and collision filters as WORLD; collision shapes are shared."
  (ccall "cn_world_copy" (int-arg world 'copy-world "world")))

(defun world-alive-p (world)
  "True if WORLD is the handle of a live world."
  (and (typep world '(signed-byte 32))
       (= 1 (ccall "cn_world_alive" world))))

(defun world-count ()
  "Number of live worlds."
  (ccall "cn_world_count"))

(defmacro with-world ((var &rest args) &body body)
  "Bind VAR to a new world (MAKE-WORLD ARGS), run BODY, destroy the world afterwards."
  `(let ((,var (make-world ,@args)))
     (unwind-protect (progn ,@body) (destroy-world ,var))))

(defun world-gravity (world)
  "Gravity of WORLD as a DVEC x y z."
  (with-out-dvec (v 3)
    (with-vector-pointers ((p v)) (ccall "cn_world_get_gravity" world p))))

(defun set-world-gravity (world gravity)
  "Set WORLD's gravity (x y z) and wake every dynamic body."
  (let ((g (to-dvec gravity 3 'set-world-gravity "gravity")))
    (ccall "cn_world_set_gravity" world (aref g 0) (aref g 1) (aref g 2))
    gravity))

(defun step-world (world &optional (dt 0.01d0))
  "Advance WORLD by one physics step of DT seconds."
  (ccall "cn_world_step" world (real-arg dt 'step-world "dt"))
  world)

(defun simulate (world seconds &optional (dt (/ 1d0 240)))
  "Advance WORLD by ceil(SECONDS/DT) steps of DT; return the number of steps. Stepping stops
early once every dynamic body sleeps or has moved slower than 1 mm/s and 0.01 rad/s for 0.1 s
of simulated time: the remaining steps would leave the world as it is."
  (ccall "cn_world_simulate" world (real-arg seconds 'simulate "seconds")
         (real-arg dt 'simulate "dt")))

(defun world-object-count (world)
  "Number of live objects (bodies and articulated objects) in WORLD."
  (ccall "cn_world_num_objects" world))

(defun world-body-count (world)
  "Number of Bullet rigid bodies in WORLD (plain bodies plus articulated objects' link bodies)."
  (ccall "cn_world_num_bodies" world))

(defun world-objects (world)
  "List of the handles of the live objects of WORLD."
  (let* ((n (ccall "cn_world_num_objects" world))
         (v (make-array n :element-type '(signed-byte 32))))
    (with-vector-pointers ((p v)) (ccall "cn_world_objects" world p n))
    (coerce v 'list)))

;;; ---- objects ------------------------------------------------------------------------------

(defun object-kind (world object)
  "Kind of OBJECT: :BODY or :ARTICULATED."
  (if (zerop (ccall "cn_object_kind" world object)) :body :articulated))

(defun remove-object (world object)
  "Remove OBJECT (a body or articulated object) from WORLD with its attachments."
  (ccall "cn_object_remove" world object)
  nil)

(defun object-pose (world object &optional out)
  "Pose of a body (or base pose of an articulated object) as a DVEC x y z qx qy qz qw,
written into OUT (a DVEC of 7) when given."
  (let ((v (or out (make-dvec 7))))
    (declare (type dvec v))
    (with-vector-pointers ((p v)) (ccall "cn_object_get_pose" world object p))
    v))

(defun set-object-pose (world object pose)
  "Teleport OBJECT to POSE (7 numbers, or ((x y z) (qx qy qz qw))); wakes it up and moves
the objects rigidly attached to it."
  (let ((v (if (and (typep pose 'dvec) (= (length pose) 7))
               pose                     ; the common case, without a call of POSE-VEC
               (pose-vec pose 'set-object-pose))))
    (declare (type dvec v))
    (with-vector-pointers ((p v)) (ccall "cn_object_set_pose" world object p))
    pose))

(defun object-poses (world objects &optional out)
  "Poses of OBJECTS (a sequence of handles) as one DVEC of 7 per object, concatenated."
  (let* ((ov (to-ivec objects 'object-poses "objects"))
         (n (length ov))
         (v (or out (make-dvec (* 7 n)))))
    (declare (type dvec v))
    (when (< (length v) (* 7 n))
      (arg-error 'object-poses "output vector holds ~d doubles, needs ~d" (length v) (* 7 n)))
    (with-vector-pointers ((po ov) (pv v)) (ccall "cn_object_get_poses" world po n pv))
    v))

(defun set-object-poses (world objects poses)
  "Teleport every object of OBJECTS to its pose in POSES (a DVEC of 7 per object, or a list
of poses).  Nothing moves if any handle or pose is invalid."
  (let* ((ov (to-ivec objects 'set-object-poses "objects"))
         (n (length ov))
         (pv (if (typep poses 'dvec)
                 poses
                 (to-dvec (loop for p in (coerce poses 'list)
                                append (coerce (pose-vec p 'set-object-poses) 'list))
                          nil 'set-object-poses "poses"))))
    (unless (= (length pv) (* 7 n))
      (arg-error 'set-object-poses "~d poses given for ~d objects" (floor (length pv) 7) n))
    (with-vector-pointers ((po ov) (pp pv)) (ccall "cn_object_set_poses" world po n pp))
    t))

(defun object-color (world object &optional (link -1))
  "RGBA colour of a body, or of LINK of an articulated object, as a DVEC of 4."
  (with-out-dvec (v 4)
    (with-vector-pointers ((p v)) (ccall "cn_object_get_color" world object link p))))

(defun set-object-color (world object color &optional (link -1))
  "Set the drawing colour (RGB or RGBA in [0,1]) of a body, or of LINK (-1 = all links) of
an articulated object."
  (let ((c (to-dvec color nil 'set-object-color "colour")))
    (unless (<= 3 (length c) 4)
      (arg-error 'set-object-color "colour ~s has ~d components, expected 3 or 4" color (length c)))
    (ccall "cn_object_set_color" world object link (aref c 0) (aref c 1) (aref c 2)
           (if (= (length c) 4) (aref c 3) 1d0))
    color))

(defun object-collision-filter (world object)
  "Collision group and mask of OBJECT as two values."
  (let ((v (make-array 2 :element-type '(signed-byte 32))))
    (with-vector-pointers ((p v)) (ccall "cn_object_get_collision_filter" world object p))
    (values (aref v 0) (aref v 1))))

(defun set-object-collision-filter (world object group mask)
  "Set the collision GROUP and MASK bits of OBJECT (all its links): two objects collide when
each one's group intersects the other's mask."
  (ccall "cn_object_set_collision_filter" world object
         (int-arg group 'set-object-collision-filter "group")
         (int-arg mask 'set-object-collision-filter "mask"))
  t)

(defun object-aabb (world object &optional (link -1))
  "Axis-aligned bounding box of OBJECT (or one LINK) as a DVEC min-x min-y min-z max-x max-y max-z."
  (with-out-dvec (v 6)
    (with-vector-pointers ((p v)) (ccall "cn_object_aabb" world object link p))))

(defun object-local-aabb (world object &optional (link -1))
  "The bounding box of OBJECT's shapes (or one LINK's) in its own frame, whatever its pose, as
a DVEC min-x min-y min-z max-x max-y max-z."
  (with-out-dvec (v 6)
    (with-vector-pointers ((p v)) (ccall "cn_object_local_aabb" world object link p))))

(defun object-active-p (world object)
  "True if a dynamic body of OBJECT is awake (still moving)."
  (= 1 (ccall "cn_object_is_active" world object)))

;;; ---- bodies --------------------------------------------------------------------------------

(defun add-plane (world &key (normal '(0 0 1)) (constant 0))
  "Add a static plane {p : normal . p = constant}; return its handle."
  (let ((n (to-dvec normal 3 'add-plane "normal")))
    (ccall "cn_body_add_plane" world (aref n 0) (aref n 1) (aref n 2)
           (real-arg constant 'add-plane "constant"))))

(defmacro with-pose-pointer ((ptr pose function) &body body)
  (let ((v (gensym "V")))
    `(let ((,v (pose-vec ,pose ,function)))
       (with-vector-pointers ((,ptr ,v)) ,@body))))

(defun add-box (world pose size &key (mass 0))
  "Add a box of full SIZE (x y z) at POSE; MASS 0 = static.  Returns the body handle."
  (let ((s (to-dvec size 3 'add-box "size")))
    (with-pose-pointer (p pose 'add-box)
      (ccall "cn_body_add_box" world p (aref s 0) (aref s 1) (aref s 2)
             (real-arg mass 'add-box "mass")))))

(defun add-sphere (world pose radius &key (mass 0))
  "Add a sphere of RADIUS at POSE; MASS 0 = static.  Returns the body handle."
  (with-pose-pointer (p pose 'add-sphere)
    (ccall "cn_body_add_sphere" world p (real-arg radius 'add-sphere "radius")
           (real-arg mass 'add-sphere "mass"))))

(defun add-cylinder (world pose radius height &key (mass 0))
  "Add a cylinder (axis = local z) at POSE; MASS 0 = static.  Returns the body handle."
  (with-pose-pointer (p pose 'add-cylinder)
    (ccall "cn_body_add_cylinder" world p (real-arg radius 'add-cylinder "radius")
           (real-arg height 'add-cylinder "height") (real-arg mass 'add-cylinder "mass"))))

(defun add-cone (world pose radius height &key (mass 0))
  "Add a cone (axis = local z, apex up) at POSE; MASS 0 = static.  Returns the body handle."
  (with-pose-pointer (p pose 'add-cone)
    (ccall "cn_body_add_cone" world p (real-arg radius 'add-cone "radius")
           (real-arg height 'add-cone "height") (real-arg mass 'add-cone "mass"))))

(defun add-mesh (world pose path &key (mass 0) (scale 1) single-hull)
  "Add a mesh body from PATH (STL, OBJ or DAE; package:// and file:// URIs work) at POSE.
SCALE is a number or (sx sy sz).  Movable bodies get one convex hull per sub-mesh of the file
(its meshes as assimp reads them: OBJ objects and groups, DAE geometries), static ones (MASS 0)
the exact triangle mesh.  SINGLE-HULL true: one convex hull over every vertex of every
sub-mesh instead, movable or static.  Shapes are cached by path, scale and kind of shape."
  (let ((s (if (realp scale) (make-array 3 :element-type 'double-float
                                           :initial-element (coerce scale 'double-float))
               (to-dvec scale 3 'add-mesh "scale"))))
    (with-pose-pointer (p pose 'add-mesh)
      (ccall "cn_body_add_mesh_flags" world p (path-arg path 'add-mesh "mesh path")
             (aref s 0) (aref s 1) (aref s 2) (real-arg mass 'add-mesh "mass")
             (if single-hull 1 0)))))

(defun add-convex-hull (world pose points &key (mass 0))
  "Add the convex hull of POINTS (a list of (x y z) or a flat DVEC) at POSE."
  (let ((v (if (typep points 'dvec) points
               (to-dvec (loop for p in (coerce points 'list) append (coerce p 'list))
                        nil 'add-convex-hull "points"))))
    (with-pose-pointer (p pose 'add-convex-hull)
      (with-vector-pointers ((pp v))
        (ccall "cn_body_add_convex_hull" world p pp (floor (length v) 3)
               (real-arg mass 'add-convex-hull "mass"))))))

(defun body-velocity (world body)
  "Linear and angular velocity of BODY as a DVEC of 6."
  (with-out-dvec (v 6)
    (with-vector-pointers ((p v)) (ccall "cn_body_get_velocity" world body p))))

(defun set-body-velocity (world body velocity)
  "Set linear and angular VELOCITY (6 numbers) of a dynamic BODY and wake it."
  (let ((v (to-dvec velocity 6 'set-body-velocity "velocity")))
    (with-vector-pointers ((p v)) (ccall "cn_body_set_velocity" world body p))
    velocity))

(defun body-mass (world body)
  "Mass of BODY in kg (0 = static)."
  (let ((v (make-dvec 1)))
    (with-vector-pointers ((p v)) (ccall "cn_body_get_mass" world body p))
    (aref v 0)))

(defun body-shape (world body)
  "Shape of BODY as two values: a keyword (:plane :box :sphere :cylinder :cone :mesh :hull)
and a list of dimensions (box: full sizes; sphere: radius; cylinder/cone: radius height;
plane: normal and constant; mesh: scale)."
  (let* ((v (make-dvec 4))
         (k (with-vector-pointers ((p v)) (ccall "cn_body_shape" world body p))))
    (values (nth k '(:plane :box :sphere :cylinder :cone :mesh :hull))
            (subseq (coerce v 'list) 0 (nth k '(4 3 1 2 2 3 0))))))
