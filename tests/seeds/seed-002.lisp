;;;; Seed 002: the intermediate "Bullet world demonstration" tutorial, a side-by-side diff of
;;;; its 2019 and 2023 revisions. The newer (right) revision is replayed, under `roslaunch
;;;; launch/world.launch' on a private master (the page's first, unchanged step).
;;;;
;;;; The diff shows only the changed hunks (two rows of context around each change), so most
;;;; blocks appear in pieces: their page lines are taken explicitly below (LINES-BLOCK), and
;;;; the rows between hunks are completed from the CRAM sources of that era
;;;; (cram_tutorials/cram_bullet_world_tutorial, noetic) and the page's own prose. Steps of the
;;;; page that no hunk shows at all (spawning the mug, ...) run as unlisted setup, so that the
;;;; blocks the page does show meet the world they expect.

(require :sb-posix)
(require :sb-bsd-sockets)

(in-package :seeds)

(define-seed "002" :format :nbsp :side :new
  :blocks (list (lines-block lines 5 12)     ;  1 spawn the robot with parked arms (tail)
                (lines-block lines 16 16)    ;  2 the kitchen object
                (lines-block lines 19 21)    ;  3 open the fridge door
                (lines-block lines 25 28)    ;  4 is mug-1 visible? NIL
                (lines-block lines 29 41)    ;  5 costmap metadata
                (lines-block lines 44 48)    ;  6 a location to see the island surface (middle)
                (lines-block lines 63 63)    ;  7 move the robot to see the mug (hidden by the diff)
                (lines-block lines 71 72)    ;  8 restart the world, fork mesh
                (lines-block lines 79 81)    ;  9 open the drawer
                (lines-block lines 89 91)    ; 10 spawn the fork in the drawer
                (lines-block lines 101 103)  ; 11 attach the fork to the drawer
                (lines-block lines 107 109)  ; 12 close the drawer a bit
                (lines-block lines 113 114)  ; 13 the attachment query
                (lines-block lines 118 120)  ; 14 detach the fork
                (lines-block lines 147 147)  ; 15 TF lookup without a TF context
                (lines-block lines 151 152)  ; 16 TF lookup in the projection environment
                (lines-block lines 168 168)  ; 17 clean the world (only its </code> is shown)
                (lines-block lines 173 177)  ; 18 the bottle
                (lines-block lines 181 181)  ; 19 simulate
                (lines-block lines 185 187)  ; 20 the base pose
                (lines-block lines 190 193)  ; 21 the look pose
                (lines-block lines 204 221)  ; 22 arms out of sight, drive, look
                (lines-block lines 227 227)  ; 23 what drive calls internally
                (lines-block lines 233 237)  ; 24 detect the bottle
                (lines-block lines 243 244))) ; 25 torso up

;;; ------------------------------------------------------------------------------------------
;;; Helpers of the checks

(defun obj (name) (btr:object (world) (tut name)))
(defun joint (object name) (btr:joint-state object name))
(defun answers (query) (cut:force-ll (prolog:prolog query)))
(defun visible-p (name)
  (answers `(and (btr:bullet-world ?w) (rob-int:robot ?r) (btr:visible ?w ?r ,(tut name)))))
(defun stable-p (name) (answers `(and (btr:bullet-world ?w) (btr:stable ?w ,(tut name)))))
(defun link-xyz (object link) (xyz (btr:link-pose object link)))
(defun park-states (arm)
  (cut:var-value '?j (cut:lazy-car (prolog:prolog `(and (rob-int:robot ?r)
                                                       (rob-int:robot-joint-states ?r :arm ,arm :park ?j))))))

(defun setup (label text)
  "A step of the page that no hunk of the diff shows, pasted as the user did, uncounted."
  (format t "~&;; --- seed 002 setup: ~a~%" label)
  (replay-text text :package "BTW-TUT"))

;;; The user works in BTW-TUT from the page's start (its in-package step is before the first hunk).
(defmacro tut-block (index (&rest options) &body checks)
  `(replay-block ,index (,@options :package "BTW-TUT") ,@checks))

;;; ------------------------------------------------------------------------------------------
;;; Before the first hunk: roslaunch, loading the tutorial, startup-ros, the world's parts.

(start-private-ros "launch/world.launch")
(setup "load the tutorial and start ROS"
       "CL-USER> (ros-load:load-system \"cram_bullet_world_tutorial\" :cram-bullet-world-tutorial)
CL-USER> (in-package :cram-bullet-world-tutorial)
BTW-TUT> (roslisp-utilities:startup-ros)")

(tut-block 1 (:name "spawn the robot with both arms parked"
                 :completions
                 '((1 "(cram-robot-interfaces:robot ?robot)"
                    "BTW-TUT> (let ((robot-urdf
                 (cl-urdf:parse-urdf
                  (roslisp:get-param \"robot_description\"))))
           (prolog:prolog
            `(and (btr:bullet-world ?world)
                  (cram-robot-interfaces:robot ?robot)")))
  (expect (cut:lazy-car (first (result-values result))) "the robot query has no answer")
  (let ((pr2 (robot-object)))
    (expect pr2 "no robot object")
    (expect (= 1 (count-if (lambda (o) (typep o 'btr:robot-object))
                           (remove (obj :iai-kitchen) (btr:objects (world)))))
            "more than one robot in the world")
    (dolist (arm '(:left :right))
      (let ((park (park-states arm)))
        (expect (= 7 (length park)) "~a park states: ~s" arm park)
        (dolist (js park)
          (expect (< (abs (- (joint pr2 (first js)) (second js))) 1e-6) "~a not parked" (first js)))))))

;;; Manipulating the kitchen

(tut-block 2 (:name "the kitchen object is :iai-kitchen")
  (let ((k (first (result-values result))))
    (expect (typep k 'btr:robot-object) "got ~s" k)
    (expect (eq (btr:name k) :iai-kitchen) "named ~s" (btr:name k))))

(tut-block 3 (:name "open the fridge door")
  (expect (< (abs (- (joint (obj :iai-kitchen) "iai_fridge_door_joint") 0.3)) 1e-6)
          "the fridge door joint is at ~a, not 0.3" (joint (obj :iai-kitchen) "iai_fridge_door_joint")))

;;; Spawning a mug, on the island (hunks the diff does not show; the 2019 and 2023 pages agree)

(setup "spawn the mug and let it fall on the island"
       "BTW-TUT> (prolog:prolog '(and (btr:bullet-world ?world)
                              (assert (btr:object ?world :mesh mug-1 ((-1 1 1) (0 0 0 1))
                                                  :mass 0.2 :color (1 0 0) :mesh :mug))))
BTW-TUT> (prolog:prolog '(and (btr:bullet-world ?world)
                              (btr:simulate ?world 10)))")

(tut-block 4 (:name "mug-1 is not visible from the start pose: NIL")
  (expect (string= "NIL" (shown-output result)) "the page shows ~s" (shown-output result))
  (expect (null (cut:force-ll (first (result-values result)))) "the query answered ~s"
          (cut:force-ll (first (result-values result)))))

;;; Abstract entity descriptions

(tut-block 5 (:name "costmap metadata in the user's package, used by the costmaps")
  (let ((p (find-package "BTW-TUT")))
    (dolist (name '("COSTMAP-SIZE" "COSTMAP-IN-REACH-DISTANCE" "ORIENTATION-SAMPLES"))
      (expect (find-symbol name p) "~a is not a symbol of BTW-TUT" name)))
  ;; the values the user stated are what the costmap layer reads, where the PR2's own differ
  (let ((rob-int:*robot-name* :pr2))
    (expect (= 0.7 (costmap:costmap-metadata-value 'costmap:costmap-in-reach-distance))
            "the costmaps read in-reach-distance ~a, the user stated 0.7"
            (costmap:costmap-metadata-value 'costmap:costmap-in-reach-distance))
    (expect (= 2 (costmap:costmap-metadata-value 'costmap:orientation-samples))
            "the costmaps read orientation-samples ~a, the user stated 2"
            (costmap:costmap-metadata-value 'costmap:orientation-samples))
    (expect (equal '(12 12) (costmap:costmap-metadata-value 'costmap:costmap-size :arity 2))
            "costmap size ~a" (costmap:costmap-metadata-value 'costmap:costmap-size :arity 2))))

(defvar *island-top* 0.84 "The height of the kitchen island's surface (model facts).")

(tut-block 6 (:name "a location to see the island surface"
                 :completions
                 '((1 "(type counter-top)"
                    "BTW-TUT>
(let* ((?on-counter (desig:a location
                             (on (desig:an object
                                           (type counter-top)")
                   (5 "(visible-for pr2)"
                    "                                 (visible-for pr2)
                                 (location ?on-counter))))
  (desig:reference location-to-see))")))
  (let ((pose (first (result-values result))))
    (expect (typep pose 'cl-transforms-stamped:pose-stamped) "got ~s" pose)
    (expect (string= "map" (cl-transforms-stamped:frame-id pose)) "frame ~s" (cl-transforms-stamped:frame-id pose))
    (destructuring-bind (x y z) (xyz pose)
      (expect (< (abs z) 1e-6) "a base pose on the floor, z ~a" z)
      ;; within VISIBILITY-COSTMAP-SIZE (2 m) of the island top, outside it
      (expect (and (< -3.5 x 1.4) (< -1.6 y 4.9)) "~a ~a is not within 2 m of the island" x y)
      (expect (not (and (< -1.5 x -0.64) (< 0.47 y 2.93))) "~a ~a stands in the island" x y)
      ;; it faces the island: its heading ray meets the island top within 2.5 m
      (let ((a (yaw pose)))
        (expect (loop for d from 0 to 2.5 by 0.02
                      thereis (let ((px (+ x (* d (cos a)))) (py (+ y (* d (sin a)))))
                                (and (<= -1.47 px -0.67) (<= 0.5 py 2.9))))
                "the robot at ~a ~a facing ~a does not face the island" x y a)))
    ;; the robot standing there does not collide with the kitchen
    (let* ((pr2 (robot-object)) (old (btr:pose pr2)))
      (unwind-protect
           (progn (setf (btr:pose pr2) pose)
                  (expect (null (answers `(and (btr:bullet-world ?w) (btr:contact ?w ,(btr:name pr2) :iai-kitchen))))
                          "the robot at ~a touches the kitchen" (xyz pose)))
        (setf (btr:pose pr2) old)))))

(tut-block 7 (:name "move the robot where it sees the mug: visible"
                 :completions
                 '((1 "<code lisp>"
                    "BTW-TUT>
(let* ((?mug-pose (btr:pose (btr:object btr:*current-bullet-world* 'mug-1)))
       (?pose-to-see-mug (desig:reference
                          (desig:a location
                                   (visible-for pr2)
                                   (location (desig:a location (pose ?mug-pose)))))))
  (btr-utils:move-robot ?pose-to-see-mug)
  (urdf-proj:with-simulated-robot
    (urdf-proj::look-at (cl-transforms-stamped:pose->pose-stamped \"map\" 0.0 ?mug-pose) nil)))
BTW-TUT> (prolog:prolog '(and (btr:bullet-world ?world)
                              (rob-int:robot ?robot)
                              (btr:visible ?world ?robot mug-1)))")))
  (let ((answer (cut:lazy-car (first (result-values result)))))
    (expect answer "mug-1 is not visible from the designator's pose")
    (expect (typep (binding "?WORLD" answer) 'btr:bt-reasoning-world) "?world is ~s" (binding "?WORLD" answer))
    (expect (> (cl-transforms:v-dist (cl-transforms:origin (btr:pose (robot-object))) (cl-transforms:make-identity-vector))
               0.5)
            "the robot did not move")))

;;; Attaching objects to the robot

(tut-block 8 (:name "restart the world, the fork mesh")
  (expect (null (obj 'mug-1)) "mug-1 is still there after the restart")
  (expect (< (abs (joint (obj :iai-kitchen) "iai_fridge_door_joint")) 1e-9) "the fridge door is still open")
  (expect (near (xyz (btr:pose (robot-object))) '(0 0 0) 1e-6) "the robot is not back at the origin")
  (expect (assoc :fork-plastic btr:*mesh-files*) "no :fork-plastic mesh"))

(defvar *drawer-link* "sink_area_left_upper_drawer_main")
(defvar *drawer-at-0.4* nil)

(tut-block 9 (:name "open the drawer to 0.4 m")
  (let ((k (obj :iai-kitchen)))
    (expect (< (abs (- (joint k "sink_area_left_upper_drawer_main_joint") 0.4)) 1e-6) "drawer joint ~a"
            (joint k "sink_area_left_upper_drawer_main_joint"))
    (setf *drawer-at-0.4* (link-xyz k *drawer-link*))))

(tut-block 10 (:name "spawn the fork in the open drawer"
                  :completions
                  '((2 "(assert (btr:object ?world :mesh fork-((1.0 0.9 0.75) (0 0 0 1))"
                     "                     (assert (btr:object ?world :mesh fork-1 ((1.0 0.9 0.75) (0 0 0 1))")))
  (expect (cut:lazy-car (first (result-values result))) "the assert has no answer")
  (expect (near (xyz (btr:pose (obj 'fork-1))) '(1.0 0.9 0.75) 1e-6) "fork-1 at ~a" (xyz (btr:pose (obj 'fork-1)))))

(defvar *fork-before* nil)

(tut-block 11 (:name "attach the fork to the drawer link")
  (expect (cut:lazy-car (first (result-values result))) "the assert has no answer")
  (expect (answers `(and (btr:bullet-world ?w) (btr:attached ?w :iai-kitchen ,*drawer-link* ,(tut 'fork-1))))
          "fork-1 is not attached to ~a" *drawer-link*)
  (setf *fork-before* (xyz (btr:pose (obj 'fork-1)))))

(tut-block 12 (:name "closing the drawer to 0.3 carries the fork along")
  (let* ((k (obj :iai-kitchen))
         (drawer-delta (mapcar #'- (link-xyz k *drawer-link*) *drawer-at-0.4*))
         (fork-delta (mapcar #'- (xyz (btr:pose (obj 'fork-1))) *fork-before*)))
    (expect (< (abs (- (joint k "sink_area_left_upper_drawer_main_joint") 0.3)) 1e-6) "drawer joint")
    (expect (< (abs (- (sqrt (reduce #'+ (mapcar (lambda (d) (* d d)) drawer-delta))) 0.1)) 1e-6)
            "the drawer moved ~a" drawer-delta)
    (expect (near fork-delta drawer-delta 1e-6) "the fork moved ~a, the drawer ~a" fork-delta drawer-delta)))

(tut-block 13 (:name "the attachment query answers")
  (let ((answer (cut:lazy-car (first (result-values result)))))
    (expect answer "no attachment between :iai-kitchen and fork-1")
    (expect (typep (binding "?WORLD" answer) 'btr:bt-reasoning-world) "?world ~s" (binding "?WORLD" answer))))

(tut-block 14 (:name "detach the fork from the kitchen")
  (expect (cut:lazy-car (first (result-values result))) "the retract has no answer")
  (expect (null (answers `(and (btr:bullet-world ?w) (btr:attached ?w :iai-kitchen ?_ ,(tut 'fork-1)))))
          "fork-1 is still attached")
  ;; the drawer moves without it now
  (let ((fork (xyz (btr:pose (obj 'fork-1)))))
    (btr:set-robot-state-from-joints '(("sink_area_left_upper_drawer_main_joint" 0.4)) (obj :iai-kitchen))
    (expect (near fork (xyz (btr:pose (obj 'fork-1))) 1e-9) "the detached fork moved with the drawer")))

;;; Using TF in the Bullet world

(tut-block 15 (:name "no TF transform outside the projection environment: an error"
                  :completions
                  '((1 "BTW-TUT> (cl-tf:lookup-transform cram-tf:*transformer* \"map\" \"l_gripper_tool_frame\""
                     "BTW-TUT> (cl-tf:lookup-transform cram-tf:*transformer* \"map\" \"l_gripper_tool_frame\")"))
                  :evaluate nil)
  ;; "does not work (unless you have a real robot running)": no robot publishes TF here
  (let ((form (first (result-forms result))))
    (expect (handler-case (progn (let ((*package* (find-package "BTW-TUT"))) (eval form)) nil)
              (error (e) (format t "~&;; as the page says, it does not work: ~a~%" e) t))
            "the lookup outside with-simulated-robot succeeded")))

(tut-block 16 (:name "the left tool frame in the projection environment")
  (let ((tf (first (result-values result)))
        (link (link-xyz (robot-object) "l_gripper_tool_frame")))
    (expect (typep tf 'cl-transforms-stamped:transform-stamped) "got ~s" tf)
    (expect (string= "map" (cl-transforms-stamped:frame-id tf)) "frame ~s" (cl-transforms-stamped:frame-id tf))
    (let ((tr (cl-transforms:translation tf)))
      (expect (near (list (cl-transforms:x tr) (cl-transforms:y tr) (cl-transforms:z tr)) link 1e-6)
              "translation ~a, the link is at ~a" tr link))))

;;; Moving the robot in the Bullet world

(tut-block 17 (:name "clean the world"
                  :completions '((1 "</code>" "BTW-TUT> (btr-utils:kill-all-objects)")))
  (expect (notany (lambda (o) (typep o 'btr:item)) (btr:objects (world))) "items are left")
  (expect (and (robot-object) (obj :iai-kitchen)) "the robot or the kitchen went too"))

(tut-block 18 (:name "spawn the bottle and put it on the table"
                  :completions
                  '((1 "BTW-TUT> (add-objects-to-mesh-list)"
                     "BTW-TUT> (add-objects-to-mesh-list)
BTW-TUT> (btr-utils:spawn-object 'bottle-1 :bottle)")
                    (4 "(cl-transforms:make-3d-vector -2 -0.83)"
                     "                                 (cl-transforms:make-3d-vector -2 -0.9 0.83)")))
  (expect (near (xyz (btr:pose (obj 'bottle-1))) '(-2 -0.9 0.83) 1e-6) "bottle-1 at ~a"
          (xyz (btr:pose (obj 'bottle-1)))))

(tut-block 19 (:name "simulate 10 s: nothing moves unexpectedly")
  (let ((p (xyz (btr:pose (obj 'bottle-1)))))
    (expect (near p '(-2 -0.9 0.86) 0.05) "bottle-1 came to rest at ~a" p)
    (expect (stable-p 'bottle-1) "bottle-1 is not stable")))

(tut-block 20 (:name "the base pose"
                  :completions
                  '((3 "\"map\""
                     "                \"map\"
                0.0
                (cl-transforms:make-3d-vector -1.8547d0 -0.381d0 0.0d0)
                (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) (/ pi -2))))")))
  (let ((p (symbol-value (tut '?grasp-base-pose))))
    (expect (typep p 'cl-transforms-stamped:pose-stamped) "got ~s" p)
    (expect (near (xyz p) '(-1.8547 -0.381 0) 1e-6) "at ~a" (xyz p))))

(tut-block 21 (:name "the look pose"
                  :completions
                  '((3 "\"base_footprint\""
                     "                \"base_footprint\"
                0.0
                (cl-transforms:make-3d-vector 0.65335d0 0.076d0 0.758d0)")))
  (let ((p (symbol-value (tut '?grasp-look-pose))))
    (expect (string= "base_footprint" (cl-transforms-stamped:frame-id p)) "frame ~s" (cl-transforms-stamped:frame-id p))
    (expect (near (xyz p) '(0.65335 0.076 0.758) 1e-6) "at ~a" (xyz p))))

(tut-block 22 (:name "arms out of sight, drive, look at the bottle"
               :completions '((16 "0.05106258161229582d0)"
                               "                           0.05106258161229582d0))")))
  (let ((pr2 (robot-object)))
    (expect (near (xyz (btr:pose pr2)) '(-1.8547 -0.381 0) 1e-6) "the robot is at ~a" (xyz (btr:pose pr2)))
    (expect (< (abs (+ (yaw (btr:pose pr2)) (/ pi 2))) 1e-6) "the robot faces ~a" (yaw (btr:pose pr2)))
    (loop for j in '("l_shoulder_pan_joint" "l_shoulder_lift_joint" "l_upper_arm_roll_joint" "l_elbow_flex_joint")
          for v in '(1.9652919379395388d0 -0.26499816732737785d0 1.3837617139225473d0 -2.1224566064321584d0)
          do (expect (< (abs (- (joint pr2 j) v)) 1e-6) "~a at ~a, not ~a" j (joint pr2 j) v))
    (loop for j in '("r_shoulder_pan_joint" "r_shoulder_lift_joint" "r_upper_arm_roll_joint" "r_elbow_flex_joint")
          for v in '(-1.712587449591307d0 -0.2567290370386635d0 -1.4633501125737374d0 -2.1221670650093913d0)
          do (expect (< (abs (- (joint pr2 j) v)) 1e-6) "~a at ~a, not ~a" j (joint pr2 j) v))
    (expect (> (abs (joint pr2 "head_tilt_joint")) 0.1) "the head did not tilt down to the bottle")
    (expect (visible-p 'bottle-1) "the bottle is not in view after looking")))

(equivalent-block 23 (:name "drive asserts the robot's object pose"
                      :reason "an illustration with unbound ?world ?robot ?target-pose of what drive calls")
  ;; the page's query, with the variables bound as drive binds them
  (let* ((form (let ((*package* (find-package "BTW-TUT"))) (read-from-string text)))
         (goal (second (second form)))
         (target (cl-transforms-stamped:make-pose-stamped
                  "map" 0.0 (cl-transforms:make-3d-vector -1.9 -0.45 0)
                  (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) (/ pi -2))))
         (pr2 (robot-object))
         (old (btr:pose pr2)))
    (expect (eq (first form) 'prolog:prolog) "not a prolog query: ~s" form)
    (expect (cut:lazy-car (prolog:prolog goal `((,(intern "?WORLD" "BTW-TUT") . ,(world))
                                                (,(intern "?ROBOT" "BTW-TUT") . ,(btr:name pr2))
                                                (,(intern "?TARGET-POSE" "BTW-TUT") . ,target))))
            "the page's query has no answer")
    (expect (near (xyz (btr:pose pr2)) '(-1.9 -0.45 0) 1e-6) "the robot is at ~a" (xyz (btr:pose pr2)))
    (setf (btr:pose pr2) old)))

(tut-block 24 (:name "detect the bottle")
  (let ((d (symbol-value (tut '*perceived-object*))))
    (expect (typep d 'desig:object-designator) "got ~s" d)
    (expect (eq (desig:desig-prop-value d :type) :bottle) "type ~s" (desig:desig-prop-value d :type))
    (expect (string= (symbol-name (desig:desig-prop-value d :name)) "BOTTLE-1") "name ~s" (desig:desig-prop-value d :name))))

(tut-block 25 (:name "push the torso up to 0.3")
  (expect (< (abs (- (joint (robot-object) "torso_lift_joint") 0.3)) 1e-6) "torso at ~a"
          (joint (robot-object) "torso_lift_joint")))

(finish-seed)
