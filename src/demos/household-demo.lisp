;;;; The household demo: initialize the kitchen, spawn the breakfast objects in their closed
;;;; containers, set the table by transporting each, then clean it up in reverse order.

(in-package :cram-projection-demos)

(defparameter *demo-visibility-threshold* 0.5
  "BTR:*VISIBILITY-THRESHOLD* during the demo. Objects in containers are partly hidden by
them: CRAM's demo uses 0.7; in this kitchen, built as boxes to the upstream bounding boxes,
the fridge door shelf's front hides the lower half of the milk carton and the pull-out's
barriers and front panel hide about half of the cereal box from any base pose, so 0.5.")

(defun demo-error (control &rest arguments)
  (error 'simple-error :format-control control :format-arguments arguments))

(defun kitchen ()
  (or (btr:get-environment-object)
      (demo-error "The household demo needs the kitchen in the belief state: call ~
                   (btw-tut:init-projection) first.")))

(defun initialize ()
  "Remove every object of the belief state but the robot and the kitchen, drop all
attachments, close the demo's drawers and doors (*HOUSEHOLD-JOINTS* to 0) and start afresh
with the designators."
  (let* ((world btr:*current-bullet-world*)
         (kitchen (kitchen))
         (robot (btr:get-robot-object)))
    (when robot (btr:detach-all-objects robot))
    (btr:detach-all-objects kitchen)
    (dolist (o (btr:objects world))
      (when (typep o 'btr:item)
        (btr:remove-object world (btr:name o))))
    (btr:set-robot-state-from-joints
     (loop for joint in *household-joints*
           when (ignore-errors (btr:joint-state kitchen joint))
             collect (list joint 0d0))
     kitchen)
    (clrhash pp-plans::*gripped-objects*)
    world))

(defun link-relative-pose (link pose)
  "The map pose of POSE ((x y z) (qx qy qz qw)) given in the frame of the kitchen LINK."
  (destructuring-bind ((x y z) (qx qy qz qw)) pose
    (cl-transforms:transform-pose
     (cl-transforms:pose->transform (btr:link-pose (kitchen) link))
     (cl-transforms:make-pose (cl-transforms:make-3d-vector x y z)
                              (cl-transforms:make-quaternion qx qy qz qw)))))

(defun spawn-objects-on-fixed-spots (&key (object-types *demo-object-types*))
  "Spawn each of OBJECT-TYPES as :TYPE-1 at its pose of *OBJECT-SPAWNING-POSES* and attach it
to its container link of the kitchen, so it moves with the drawer or door. No physics runs.
Returns the objects."
  (let ((kitchen (kitchen)))
    (unless (assoc :bowl btr:*mesh-files*)
      (btw-tut:add-objects-to-mesh-list))
    (loop for type in object-types
          for (nil link pose) = (or (assoc type *object-spawning-poses*)
                                    (demo-error "The household demo has no spawning pose for ~
                                                 ~s; known: ~{~s~^, ~}." type
                                                (mapcar #'first *object-spawning-poses*)))
          for object = (btr:add-object btr:*current-bullet-world* :mesh (demo-object-name type)
                                       (link-relative-pose link pose)
                                       :mesh type :mass 0.2 :types (list type))
          do (btr:attach-object kitchen object :link link)
          collect object)))

(defun park-robot ()
  "Arms parked, torso up, base at the map origin, grippers open, looking forward, in
parallel; failures are ignored."
  (let ((?origin (cl-transforms-stamped:make-pose-stamped
                  cram-tf:*fixed-frame* 0d0 (cl-transforms:make-3d-vector 0 0 0)
                  (cl-transforms:make-identity-rotation))))
    (handler-case
        (cpl:par
          (exe:perform (desig:an action (type parking-arms)))
          (exe:perform (desig:an action (type moving-torso) (joint-angle upper-limit)))
          (exe:perform (desig:an action (type going) (target (desig:a location (pose ?origin)))))
          (exe:perform (desig:an action (type setting-gripper) (gripper (left right))
                                 (position open)))
          (exe:perform (desig:an action (type looking) (direction forward))))
      (cpl:plan-failure (e)
        (cpl:log-message :warn '(demos park-robot) "~a~%Ignoring." e)))))

(defparameter *cleaning-grasps*
  '((:cup (:left-side :right-side :back :front))
    (:breakfast-cereal (:front :back :front-flipped :back-flipped)))
  "Grasps of the cleaning transports per type (no top grasp of the cereal on the oven board).")

(defun transport (type context)
  (let ((?type type) (?context context)
        (?grasps (second (assoc type *cleaning-grasps*))))
    (exe:perform
     (if (and ?grasps (eq context :table-cleaning))
         (desig:an action (type transporting) (object (desig:an object (type ?type)))
                   (context ?context) (grasps ?grasps))
         (desig:an action (type transporting) (object (desig:an object (type ?type)))
                   (context ?context))))))

(defun transport-each (types context)
  "Transport an object of each of TYPES in turn in CONTEXT, each knowing the types that follow
\(FD-PLANS::*DELIVERIES-TO-COME*: each object is put down where it leaves the objects that
follow room on the table)."
  (loop for (type . later) on types
        do (let ((fd-plans::*deliveries-to-come* later))
             (transport type context))))

(defvar *after-setting-hook* nil
  "A function called with no arguments when the table is set, before cleaning starts (NIL:
none); the tests record the table state with it.")

(defparameter *demo-seed* 2
  "The seed HOUSEHOLD-DEMO starts its random choices from (costmap samples, inverse kinematics)
unless given another: the same seed, the same run.")

(defun seed-demo (seed)
  "Seed every random choice of a projection run from SEED (an integer) and forget cached
reachability answers, so that the same seed gives the same run."
  (unless (typep seed '(integer 0))
    (demo-error "HOUSEHOLD-DEMO: :SEED ~s, expected a non-negative integer or NIL." seed))
  (setf urdf-proj:*ik-random-state* (sb-ext:seed-random-state (+ seed 1)))
  (costmap:seed-costmaps (+ seed 2))
  ;; cached reachability answers would skip IK calls and so change the random stream
  (clrhash env-man::*reachability-cache*))

(defun household-demo (&key (object-list *demo-object-types*) varied-kitchen (seed *demo-seed*))
  "CRAM's household demo in projection: initialize the kitchen, spawn OBJECT-LIST (types, in
the order the table is set; the bowl must come before spoon and cup) in their closed
containers, park the robot, transport each object to the table (context table-setting), then
each in reverse order back (context table-cleaning). With VARIED-KITCHEN the dining table and
the kitchen island stand a little elsewhere (VARY-KITCHEN). BTR:*VISIBILITY-THRESHOLD* is
*DEMO-VISIBILITY-THRESHOLD* meanwhile, and the robot's base poses keep to the kitchen's free
floor (COSTMAP:KITCHEN-RESTRICTED-AREA, as CRAM's demo restricts them). The random choices start from SEED (NIL: as they
are). No failure is caught. Returns the object list."
  (let ((unknown (set-difference object-list (mapcar #'first *object-spawning-poses*))))
    (when unknown
      (demo-error "HOUSEHOLD-DEMO: unknown object type~p ~{~s~^, ~}; expected some of ~{~s~^, ~}."
                  (length unknown) unknown (mapcar #'first *object-spawning-poses*))))
  (unless (btr:get-environment-object)
    (btw-tut:init-projection))
  ;; set, not bound: perception runs in the process modules' threads
  (let ((threshold btr:*visibility-threshold*)
        (restricted-area costmap:*restricted-area-function*))
    (setf btr:*visibility-threshold* *demo-visibility-threshold*
          costmap:*restricted-area-function* #'costmap:kitchen-restricted-area)
    (unwind-protect
         (progn
           (when seed (seed-demo seed))
           (initialize)
           (when varied-kitchen (vary-kitchen))
           (spawn-objects-on-fixed-spots :object-types object-list)
           (urdf-proj:with-simulated-robot
             (park-robot)
             ;; what is put on the table must be graspable there as the cleaning grasps it
             (let ((fd-plans::*regrasp-grasps* *cleaning-grasps*))
               (transport-each object-list :table-setting))
             (when *after-setting-hook* (funcall *after-setting-hook*))
             (transport-each (reverse object-list) :table-cleaning)
             (park-robot)))
      (setf btr:*visibility-threshold* threshold
            costmap:*restricted-area-function* restricted-area)))
  object-list)

(defun in-dishwasher-p (position)
  "True when POSITION (a map point) lies in the closed dishwasher: within 0.35 m horizontally of
its frame and below the sink's counter top."
  (let ((d (cl-transforms:origin (btr:link-pose (kitchen) "sink_area_dish_washer_main"))))
    (and (< (sqrt (+ (expt (- (cl-transforms:x position) (cl-transforms:x d)) 2)
                     (expt (- (cl-transforms:y position) (cl-transforms:y d)) 2)))
            0.35d0)
         (< (cl-transforms:z position) 0.85d0))))
