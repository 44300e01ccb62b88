;;;; Seed 001: the 2017 "Bullet world demonstration" tutorial (Cram4 era). Its newer revision
;;;; only says the page moved, so the older revision's code is what users have: every block is
;;;; replayed as a user of that era pastes it into cram-plans, under `roslaunch
;;;; launch/world.launch' (the page's first step) on a private master.
;;;;
;;;; The diff table cut most lines short (or dropped them); the completions below restore them
;;;; from the CRAM sources of that era (cram_tutorials/cram_bullet_world_tutorial 2017,
;;;; cram_pr2_pick_place_plans) and the page's own prose.

(require :sb-posix)
(require :sb-bsd-sockets)

(in-package :seeds)

;;; Two stretches of the page are HTML comments (`<!-- ... -->', written `<html><!--' in DokuWiki,
;;; which the diff table cut to `<'): the installation notes and the last section (`Light-weight
;;; simulation'), whose two Lisp blocks readers never see. Those blocks are not blocks of the page:
;;; they are left out of N before numbering (they come last, so the others keep their numbers).

(defun comment-open-p (text)
  "Whether TEXT may open a comment: `<!--', or `<html><!--' cut short by the diff table to a
prefix of it alone on its line (such as `<', which could also be another tag cut short)."
  (let ((s (trim text)))
    (and (plusp (length s))
         (or (search "<!--" s)
             (and (<= (length s) 10) (string= s "<html><!--" :end2 (length s)))))))

(defun comment-close-p (text) (search "-->" text))

(defun html-comments (lines)
  "The commented stretches of LINES as (open-line . close-line): a possible opening counts only
when a `-->' follows it before the next possible opening (a lone `<' is also what the diff
table leaves of other tags, e.g. `<note>')."
  (let ((opens (remove-if-not (lambda (e) (comment-open-p (cdr e))) lines)))
    (loop for (o . rest) on opens
          for next = (if rest (car (first rest)) most-positive-fixnum)
          for close = (find-if (lambda (e) (and (> (car e) (car o)) (< (car e) next)
                                                (comment-close-p (cdr e))))
                               lines)
          when close collect (cons (car o) (car close)))))

(defun html-commented-p (block lines)
  "Whether BLOCK (entries of LINES) lies inside one of the page's HTML comments."
  (let ((first-line (car (first block))))
    (some (lambda (c) (< (car c) first-line (cdr c))) (html-comments lines))))

(define-seed "001" :format :table :side :old
  :blocks (remove-if (lambda (b) (html-commented-p b lines)) (code-blocks lines)))

;;; ------------------------------------------------------------------------------------------
;;; Helpers of the checks

(defun btw (name) (find-symbol (string name) "BTW-TUT"))
(defun obj (name) (btr:object (world) (tut name)))
(defun joint (object name) (btr:joint-state object name))
(defun prolog-yes (query) (not (null (cut:force-ll (prolog:prolog query)))))
(defun rosparam-get (name)
  "The value `rosparam get NAME' prints, read back from its YAML."
  (uiop:run-program (list "sh" "-c"
                          (format nil "rosparam get '~a' | python3 -c 'import sys, yaml; sys.stdout.write(str(yaml.safe_load(sys.stdin.read())))'" name))
                    :output :string :ignore-error-status t :error-output :output))
(defun kitchen-urdf-text () (uiop:read-file-string (merge-pathnames "resources/iai_kitchen.urdf" *checkout*)))
(defun robot-urdf-text () (uiop:read-file-string (merge-pathnames "robots/pr2/pr2.urdf" *checkout*)))
(defun held-by (arm)
  "The names of the objects attached to the robot's ARM gripper."
  (let* ((robot (robot-object))
         (links (mapcar (lambda (a) (binding "?LINK" a))
                        (cut:force-ll
                         (prolog:prolog `(or (rob-int:gripper-link ,(btr:name robot) ,arm ?link)
                                             (rob-int:end-effector-link ,(btr:name robot) ,arm ?link)))))))
    ;; BTR:ATTACHED-OBJECTS gives (object-name link-name loose grasp) entries
    (remove-duplicates
     (loop for (name link) in (btr:attached-objects robot)
           when (member link links :test #'equal)
             collect (intern (symbol-name name) :seeds)))))
(defun on-island-p (name)
  "NAME rests on the kitchen island top: its origin over the top's box, above the top (z 0.851).
The box is resources/iai_kitchen.urdf's kitchen_island_surface (0.865 x 2.45 x 0.02 centred at
x -1.033, y 1.719, z 0.841 in map); the old bound x <= -0.67 cut 7 cm off the top's front edge."
  (destructuring-bind (x y z) (xyz (btr:pose (obj name)))
    (and (<= -1.466 x -0.600) (<= 0.494 y 2.944) (< 0.85 z 1.0))))
(defun stable-p (name) (prolog-yes `(and (btr:bullet-world ?w) (btr:stable ?w ,(tut name)))))

;;; ------------------------------------------------------------------------------------------
;;; REPL setup

(replay-block 1 (:name "load the tutorial, in-package"
                 :completions '((1 "CL-USER> (ros-load:" "CL-USER> (ros-load:load-system \"cram_bullet_world_tutorial\" :cram-bullet-world-tutorial)")
                                (2 "CL-USER> (in-package :" "CL-USER> (in-package :cram-bullet-world-tutorial)")))
  (expect (eq (find-package "BTW-TUT") (find-package "CRAM-BULLET-WORLD-TUTORIAL")) "no BTW-TUT package")
  (expect (string= (package-name (first (result-values result))) "CRAM-BULLET-WORLD-TUTORIAL")
          "in-package returned ~s" (result-values result)))

;; the page's shell step before block 2: `roslaunch cram_bullet_world_tutorial world.launch'
(start-private-ros "launch/world.launch")

(replay-block 2 (:name "start a ROS node (under roslaunch launch/world.launch)"
                 :completions '((1 "BTW-TUT> (roslisp:" "BTW-TUT> (roslisp:start-ros-node \"bullet_world\")")))
  ;; the page's shell steps before it: roslaunch world.launch; rosparam get the two URDFs
  ;; `rosparam get' prints the value as YAML (quoted, escaped, folded): the check reads that
  ;; YAML back (with the YAML library rosparam itself uses) and compares the texts
  (expect (string= (string-trim '(#\Newline #\Space) (rosparam-get "/kitchen_description"))
                   (string-trim '(#\Newline #\Space) (kitchen-urdf-text)))
          "rosparam get /kitchen_description is not resources/iai_kitchen.urdf")
  (expect (string= (rosparam-get "/kitchen_description") (roslisp:get-param "/kitchen_description"))
          "the node reads another /kitchen_description than rosparam shows")
  (expect (search "<robot name=\"pr2\"" (rosparam-get "/robot_description"))
          "rosparam get /robot_description is not the PR2")
  (expect (search "/bullet_world" (ros-run "rosnode" "list")) "no /bullet_world node: ~a"
          (ros-run "rosnode" "list")))

(replay-block 3 (:name "the init functions called by hand"
                 :completions '((1 "BTW-TUT> (cram-occupancy-grid-costmap::" "BTW-TUT> (cram-occupancy-grid-costmap::init-occupancy-grid-costmap)")
                                (2 "BTW-TUT> (cram-bullet-reasoning-belief-state::" "BTW-TUT> (cram-bullet-reasoning-belief-state::ros-time-init)")
                                (3 "BTW-TUT> (cram-location-costmap::" "BTW-TUT> (cram-location-costmap::location-costmap-vis-init)")
                                (4 "BTW-TUT> (cram-tf::" "BTW-TUT> (cram-tf::init-tf)")))
  (expect (= 4 (length (result-forms result))) "4 forms expected")
  (expect cram-tf:*transformer* "no TF transformer after init-tf")
  (let ((grid (funcall (find-symbol "OCCUPANCY-GRID" "CRAM-OCCUPANCY-GRID-COSTMAP"))))
    (expect grid "no occupancy grid after init-occupancy-grid-costmap")))

(replay-block 4 (:name "the current Bullet world"
                 :completions '((1 "BTW-TUT> (prolog:" "BTW-TUT> (prolog:prolog '(btr:bullet-world ?world))")))
  (let ((w (binding "?WORLD" (cut:lazy-car (first (result-values result))))))
    (expect (typep w 'btr:bt-reasoning-world) "?world is ~s" w)))

;;; Bullet world initialization

(replay-block 5 (:name "debug window"
                 :completions '((1 "BTW-TUT> (prolog:" "BTW-TUT> (prolog:prolog '(and (btr:bullet-world ?world)")
                                (2 "(btr:" "                              (btr:debug-window ?world)))")))
  (expect (cut:lazy-car (first (result-values result))) "debug-window query failed"))

(replay-block 6 (:name "the floor plane"
                 :completions '((1 "BTW-TUT> (prolog:" "BTW-TUT> (prolog:prolog '(and (btr:bullet-world ?world)")
                                (2 "(assert (btr:object ?world :" "                              (assert (btr:object ?world :static-plane :floor ((0 0 0) (0 0 0 1))")))
  (expect (cut:lazy-car (first (result-values result))) "the assert failed")
  (expect (obj :floor) "no :floor object"))

(equivalent-block 7 (:name "rgrep for (<- (assert" :reason "an Emacs search of the sources")
  ;; the definitions the user finds: the Bullet world's assert clauses in projection/btr/
  (let ((hits (remove-if-not (lambda (f) (search "(<- (assert" (uiop:read-file-string f)))
                             (directory (merge-pathnames "projection/btr/*.lisp" *checkout*)))))
    (expect hits "no (<- (assert definitions under projection/btr/")))

(equivalent-block 8 (:name "the assert object rule" :reason "a listing of the library's source")
  ;; the rule the page shows: (assert (object ?world ...)) is (assert ?world (object ...))
  ;; (the name is BTW-TUT::BOX-A, as the page's reader would type it: OBJ looks names up there)
  (cut:force-ll (prolog:prolog `(and (btr:bullet-world ?w)
                   (assert ?w (btr:object :box ,(tut 'box-a) ((2 2 0.1) (0 0 0 1)) :size (0.1 0.1 0.1) :mass 0.1)))))
  (expect (obj 'box-a) "(assert ?world (object ...)) did not spawn")
  (cut:force-ll (prolog:prolog `(and (btr:bullet-world ?w) (btr:retract (btr:object ?w ,(tut 'box-a))))))
  (expect (null (obj 'box-a)) "box-a not retracted"))

(replay-block 9 (:name "spawn the PR2 from robot_description"
                 :completions '((2 "| + |" "                 (cl-urdf:parse-urdf")
                                (3 "(roslisp:" "                  (roslisp:get-param \"robot_description\"))))")
                                (4 "| + |" "           (prolog:prolog")
                                (5 "`(and (btr:" "            `(and (btr:bullet-world ?world)")
                                (6 "(cram-robot-interfaces:" "                  (cram-robot-interfaces:robot ?robot)")
                                (7 "(assert (btr:object ?world :urdf ?robot ((0 0 0) (0 0 0 1)) :urdf ," "                  (assert (btr:object ?world :urdf ?robot ((0 0 0) (0 0 0 1)) :urdf ,robot-urdf))")
                                (8 "(cram-robot-interfaces:" "                  (cram-robot-interfaces:robot-arms-parking-joint-states ?robot ?joint-states)")
                                (9 "(assert (btr:" "                  (assert (btr:joint-state ?world ?robot ?joint-states))")
                                (10 "(assert (btr:" "                  (assert (btr:joint-state ?world ?robot ((\"torso_lift_joint\" 0.15d0)))))))")))
  (expect (cut:lazy-car (first (result-values result))) "the robot query failed")
  (let ((pr2 (robot-object)))
    (expect pr2 "no robot object")
    (expect (< (abs (- (joint pr2 "torso_lift_joint") 0.15)) 1e-6) "torso at ~a" (joint pr2 "torso_lift_joint"))
    (let ((park (cut:var-value '?j (cut:lazy-car (prolog:prolog '(and (cram-robot-interfaces:robot ?r)
                                                                     (cram-robot-interfaces:robot-arms-parking-joint-states ?r ?j)))))))
      (expect (= 14 (length park)) "parking joint states of both arms: ~s" park)
      (dolist (js park)
        (expect (< (abs (- (joint pr2 (first js)) (second js))) 1e-6) "~a not parked" (first js))))))

(equivalent-block 10 (:name "the spawning line" :reason "a repetition of a line of block 9 for the prose")
  (expect (btr:get-robot-object) "the robot of block 9 is not in the world")
  (expect (search ":urdf ?robot" text) "the block is the line that spawns the robot"))

(replay-block 11 (:name "spawn the kitchen from kitchen_description"
                  :completions '((2 "| + |" "                 (cl-urdf:parse-urdf")
                                 (3 "(roslisp:" "                  (roslisp:get-param \"kitchen_description\"))))")
                                 (4 "| + |" "           (prolog:prolog")
                                 (5 "`(and (btr:" "            `(and (btr:bullet-world ?world)")
                                 (6 "(assert (btr:object ?world :" "                  (assert (btr:object ?world :semantic-map :kitchen ((0 0 0) (0 0 0 1))")
                                 (7 ":urdf ," "                                      :urdf ,kitchen-urdf)))))")))
  (expect (obj :kitchen) "no :kitchen object")
  (expect (member "iai_fridge_door_joint" (btr:joint-names (obj :kitchen)) :test #'string=)
          "the kitchen has no fridge door joint"))

(replay-block 12 (:name "startup-ros reinitializes"
                  :completions '((1 "BTW-TUT> (roslisp-utilities:" "BTW-TUT> (roslisp-utilities:startup-ros)")))
  (expect (robot-object) "no robot after startup-ros")
  (expect (obj :kitchen) "(btr:object ... :kitchen) finds no kitchen after startup-ros"))

(replay-block 13 (:name "the registered init functions"
                  :completions '((1 "BTW-TUT> (alexandria:" "BTW-TUT> (alexandria:hash-table-keys roslisp-utilities::*ros-init-functions*)")))
  (let ((names (mapcar #'string (first (result-values result)))))
    (dolist (f '("INIT-OCCUPANCY-GRID-COSTMAP" "ROS-TIME-INIT" "LOCATION-COSTMAP-VIS-INIT" "INIT-TF" "INIT-PROJECTION"))
      (expect (member f names :test #'string=) "~a is not a registered init function: ~s" f names))))

;;; Manipulating the kitchen

(replay-block 14 (:name "the kitchen object"
                  :completions '((1 "BTW-TUT> (btr:object btr:" "BTW-TUT> (btr:object btr:*current-bullet-world* :kitchen)")))
  (expect (typep (first (result-values result)) 'btr:robot-object) "got ~s" (result-values result)))

(replay-block 15 (:name "open the fridge door"
                  :completions '((2 "(btr:" "(btr:set-robot-state-from-joints")
                                 (3 "'" " '((\"iai_fridge_door_joint\"  0.3d0))")
                                 (4 "| + |" " (btr:object btr:*current-bullet-world* :kitchen))")))
  (expect (< (abs (- (joint (obj :kitchen) "iai_fridge_door_joint") 0.3)) 1e-6) "the fridge door is not at 0.3"))

;;; Spawn and change objects in the world

(replay-block 16 (:name "fast initialization"
                  :completions '((1 "BTW-TUT> (roslisp-utilities:" "BTW-TUT> (roslisp-utilities:startup-ros)")))
  (expect (< (abs (joint (obj :kitchen) "iai_fridge_door_joint")) 1e-6) "the fridge door is still open")
  (expect (near (xyz (btr:pose (robot-object))) '(0 0 0) 1e-6) "the robot is not at the origin"))

(replay-block 17 (:name "spawn a mug above the robot"
                  :completions '((2 "(prolog:" "(prolog:prolog '(and (btr:bullet-world ?world)")
                                 (3 "| + |" "                     (assert (btr:object ?world :mesh mug-1 ((0 0 2) (0 0 0 1))")))
  (expect (near (xyz (btr:pose (obj 'mug-1))) '(0 0 2) 1e-6) "mug-1 is not at (0 0 2)"))

(replay-block 18 (:name "move the mug over the island"
                  :completions '((1 "BTW-TUT> (prolog:" "BTW-TUT> (prolog:prolog '(and (btr:bullet-world ?world)")
                                 (2 "(assert (btr:" "                              (assert (btr:object-pose ?world mug-1 ((-1 1 1) (0 0 0 1))))))")))
  (expect (near (xyz (btr:pose (obj 'mug-1))) '(-1 1 1) 1e-6) "mug-1 is not at (-1 1 1)"))

(replay-block 19 (:name "the mug instance"
                  :completions '((1 "BTW-TUT> (btr:object btr:" "BTW-TUT> (btr:object btr:*current-bullet-world* 'mug-1)")))
  (expect (eq (first (result-values result)) (obj 'mug-1)) "not the mug object"))

(replay-block 20 (:name "the mug's pose"
                  :completions '((1 "BTW-TUT> (btr:pose (btr:object btr:" "BTW-TUT> (btr:pose (btr:object btr:*current-bullet-world* 'mug-1))")))
  (let ((pose (first (result-values result))))
    (expect (typep pose 'cl-transforms:pose) "not a pose: ~s" pose)
    (expect (near (xyz pose) '(-1 1 1) 1e-9) "pose ~s" pose)
    (expect (search "#<" (shown-output result)) "the page shows a printed pose")
    (expect (search "#<" (princ-to-string pose)) "prints as ~a" pose)))

;;; Geometric reasoning

(replay-block 21 (:name "simulate: the mug falls onto the island"
                  :completions '((1 "BTW-TUT> (prolog:" "BTW-TUT> (prolog:prolog '(and (btr:bullet-world ?world)")
                                 (2 "(btr:" "                              (btr:simulate ?world 10)))")))
  (expect (on-island-p 'mug-1) "mug-1 at ~s is not on the island" (xyz (btr:pose (obj 'mug-1)))))

(replay-block 22 (:name "the scene is stable"
                  :completions '((1 "BTW-TUT> (prolog:" "BTW-TUT> (prolog:prolog '(and (btr:bullet-world ?world)")))
  (let ((answer (cut:force-ll (first (result-values result)))))
    (expect (and answer (binding "?WORLD" (first answer))) "stable gave ~s" answer)
    (expect (string= "(((?WORLD . ...)))" (shown-output result)) "page shows ~s" (shown-output result))))

(replay-block 23 (:name "the mug is not visible"
                  :completions '((1 "BTW-TUT> (prolog:" "BTW-TUT> (prolog:prolog '(and (btr:bullet-world ?world)")
                                 (2 "(cram-robot-interfaces:" "                              (cram-robot-interfaces:robot ?robot)")
                                 (3 "(btr:" "                              (btr:visible ?world ?robot mug-1)))")))
  (expect (null (first (result-values result))) "visible: ~s" (result-values result))
  (expect (string= "NIL" (shown-output result)) "the page shows ~s" (shown-output result)))

(replay-block 24 (:name "turn the PR2 to the mug; now it is visible"
                  :completions '((1 "BTW-TUT> (prolog:" "BTW-TUT> (prolog:prolog '(and (btr:bullet-world ?world)")
                                 (2 "(assert (btr:" "                              (assert (btr:object-pose ?world cram-pr2-description:pr2")
                                 (3 "((0.5 1 0) (0 0 1 ))))))" "                                                       ((0.5 1 0) (0 0 1 0))))))")))
  (expect (near (xyz (btr:pose (robot-object))) '(0.5 1 0) 1e-6) "the PR2 is at ~s" (xyz (btr:pose (robot-object))))
  ;; "ask the visibility query again"
  (expect (prolog-yes `(and (btr:bullet-world ?world) (cram-robot-interfaces:robot ?robot)
                        (btr:visible ?world ?robot ,(tut 'mug-1))))
          "the mug is still not visible"))

;;; Abstract entity descriptions

(defvar *to-see-pose* nil)

(replay-block 25 (:name "a location to see the mug"
                  :completions '((1 "BTW-TUT> (let* ((mug-pose (btr:pose (btr:object btr:" "BTW-TUT> (let* ((mug-pose (btr:pose (btr:object btr:*current-bullet-world* 'mug-1)))")
                                 (2 "(mug-pose-stamped (cl-transforms-stamped:" "                (mug-pose-stamped (cl-transforms-stamped:pose->pose-stamped \"map\" 0 mug-pose))")
                                 (3 "(mug-pose-designator (desig:" "                (mug-pose-designator (desig:make-designator :location `((:pose ,mug-pose-stamped))))")
                                 (4 "(to-see-designator (desig:" "                (to-see-designator (desig:make-designator :location `((:to :see)")
                                 (5 "(:location ," "                                                                      (:location ,mug-pose-designator)))))")
                                 (6 "| + |" "           (desig:reference to-see-designator))")))
  (let ((pose (first (result-values result))))
    (expect (typep pose 'cl-transforms-stamped:pose-stamped) "not a pose-stamped: ~s" pose)
    (expect (string= "map" (cl-transforms-stamped:frame-id pose)) "frame ~s" (cl-transforms-stamped:frame-id pose))
    (expect (search "#<" (shown-output result)) "the page shows a printed pose")
    ;; from there the robot sees the mug once it looks at it: a (:to :see) pose is a base pose
    ;; for looking at the target (the head is turned towards it, as block 24 turned the robot),
    ;; not a pose from which the parked head happens to face it
    (btr:with-copied-world ()
      (btr-utils:move-robot pose)
      (cram-urdf-projection::look-at (btr:pose (obj 'mug-1)))
      (expect (prolog-yes `(and (btr:bullet-world ?w) (cram-robot-interfaces:robot ?r) (btr:visible ?w ?r ,(tut 'mug-1))))
              "the mug is not visible from ~s" (xyz pose)))))

(replay-block 26 (:name "a location to see a mug on the island counter"
                  :completions '((2 "(let* ((on-counter (desig:" "(let* ((on-counter (desig:make-designator :location `((:on \"CounterTop\")")
                                 (3 "(:name \"" "                                                      (:name \"iai_kitchen_kitchen_island_counter_top\"))))")
                                 (4 "| + |" "       (the-object (desig:make-designator :object `((:type :mug)")
                                 (5 "(:at ," "                                                    (:at ,on-counter))))")
                                 (6 "| + |" "       (pose-to-see (desig:make-designator :location `((:to :see)")
                                 (7 "(:object ," "                                                       (:object ,the-object)))))")
                                 (8 "(desig:" "  (desig:reference pose-to-see))")))
  (let ((pose (first (result-values result))))
    (setf *to-see-pose* pose)
    (expect (typep pose 'cl-transforms-stamped:pose-stamped) "not a pose-stamped: ~s" pose)
    (expect (search "#<" (shown-output result)) "the page shows a printed pose")
    ;; a base pose near the island, facing it
    (destructuring-bind (x y z) (xyz pose)
      (expect (and (< -3.5 x 1.0) (< -0.5 y 4.0) (< (abs z) 1e-6)) "pose ~s is not near the island" (list x y z)))))

(replay-block 27 (:name "move the robot there"
                  :completions '((1 "BTW-TUT> (btr-utils:" "BTW-TUT> (btr-utils:move-robot *)")))
  (expect (near (xyz (btr:pose (robot-object))) (xyz *to-see-pose*) 1e-6) "the robot is at ~s, not ~s"
          (xyz (btr:pose (robot-object))) (xyz *to-see-pose*)))

;;; Grasp objects

(replay-block 28 (:name "clean environment"
                  :completions '((1 "BTW-TUT> (roslisp-utilities:" "BTW-TUT> (roslisp-utilities:startup-ros)")))
  (expect (null (obj 'mug-1)) "the mug survived startup-ros"))

(replay-block 29 (:name "add the tutorial meshes")
  (expect (assoc :bottle btr:*mesh-files*) "no :bottle mesh"))

(replay-block 30 (:name "spawn a bottle and move it onto the table"
                  :completions '((1 "BTW-TUT> (btr-utils:" "BTW-TUT> (btr-utils:spawn-object 'bottle-1 :bottle)")
                                 (2 "BTW-TUT> (btr-utils:" "BTW-TUT> (btr-utils:move-object 'bottle-1 (cl-transforms:make-pose")
                                 (3 "(cl-transforms:" "                                           (cl-transforms:make-3d-vector -2 -0.9 0.861667d0)")
                                 (4 "(cl-transforms:" "                                           (cl-transforms:make-identity-rotation)))")))
  (expect (near (xyz (btr:pose (obj 'bottle-1))) '(-2 -0.9 0.861667) 1e-5) "bottle-1 at ~s" (xyz (btr:pose (obj 'bottle-1)))))

(replay-block 31 (:name "simulate 100 s: the bottle stays"
                  :completions '((1 "BTW-TUT> (btr:" "BTW-TUT> (btr:simulate btr:*current-bullet-world* 100)")))
  (expect (near (xyz (btr:pose (obj 'bottle-1))) '(-2 -0.9 0.86) 0.02) "bottle-1 moved to ~s" (xyz (btr:pose (obj 'bottle-1))))
  (expect (stable-p 'bottle-1) "bottle-1 is not stable"))

(replay-block 32 (:name "the base pose near the bottle"
                  :completions '((1 "BTW-TUT> (setf ?" "BTW-TUT> (setf ?grasp-base-pose")
                                 (2 "(cl-transforms-stamped:" "               (cl-transforms-stamped:make-pose-stamped")
                                 (3 "\"" "                \"map\"")
                                 (5 "| + |" "                (cl-transforms:make-3d-vector -1.8547d0 -0.381d0 0.0d0)")
                                 (6 "| + |" "                (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) (/ pi -2))))")))
  (expect (typep (symbol-value (btw "?GRASP-BASE-POSE")) 'cl-transforms-stamped:pose-stamped) "not set"))

(replay-block 33 (:name "the point to look at"
                  :completions '((1 "BTW-TUT> (setf ?" "BTW-TUT> (setf ?grasp-look-pose")
                                 (2 "(cl-transforms-stamped:" "               (cl-transforms-stamped:make-pose-stamped")
                                 (3 "\"" "                \"base_footprint\"")
                                 (5 "| + |" "                (cl-transforms:make-3d-vector 0.65335d0 0.076d0 0.758d0)")
                                 (6 "| + |" "                (cl-transforms:make-identity-rotation)))")))
  (expect (string= "base_footprint" (cl-transforms-stamped:frame-id (symbol-value (btw "?GRASP-LOOK-POSE")))) "not set"))

(replay-block 34 (:name "park arms, drive and look in parallel"
                  :completions '((2 "(proj:" "(proj:with-projection-environment pr2-proj::pr2-bullet-projection-environment")
                                 (3 "(cpl:" "  (cpl:top-level")
                                 (5 "(pr2-pp-plans::" "      (pr2-pp-plans::park-arms)")
                                 (6 "(exe:" "      (exe:perform (desig:a motion")
                                 (8 "(target (desig:a location (pose ?" "                            (target (desig:a location (pose ?grasp-base-pose)))))")
                                 (9 "(exe:" "      (exe:perform (desig:a motion")
                                 (11 "(target (desig:a location (pose ?" "                            (target (desig:a location (pose ?grasp-look-pose))))))))")))
  (expect (near (xyz (btr:pose (robot-object))) '(-1.8547 -0.381 0) 1e-3) "the robot is at ~s" (xyz (btr:pose (robot-object))))
  (expect (prolog-yes `(and (btr:bullet-world ?w) (cram-robot-interfaces:robot ?r) (btr:visible ?w ?r ,(tut 'bottle-1))))
          "the robot does not see bottle-1"))

(replay-block 35 (:name "perceive the bottle, torso up, drive and pick up"
                  :completions '((2 "(proj:" "(proj:with-projection-environment pr2-proj::pr2-bullet-projection-environment")
                                 (3 "(cpl:" "  (cpl:top-level")
                                 (4 "(let* ((?" "    (let* ((?bottle-desig (desig:an object")
                                 (6 "| + |" "           (?perceived-bottle-desig (pr2-pp-plans::perceive ?bottle-desig)))")
                                 (7 "(exe:" "      (exe:perform")
                                 (8 "| + |" "       (desig:a motion (type moving-torso) (joint-angle 0.3)))")
                                 (9 "(pr2-pp-plans::" "      (pr2-pp-plans::drive-and-pick-up-plan ?perceived-bottle-desig :?arm :right))))")))
  (expect (equal '(bottle-1) (held-by :right)) "the right gripper holds ~s" (held-by :right)))

(replay-block 36 (:name "the drive-and-pick-up-plan listing"
                  :completions '((2 "(defun drive-and-pick-up-plan (?" "(defun drive-and-pick-up-plan (?object-designator &key (?arm :right))")
                                 (4 "(drive-towards-object-plan ?" "  (drive-towards-object-plan ?object-designator :?arm ?arm)")
                                 (6 "(exe:" "    (exe:perform (desig:an action")
                                 (8 "| + |" "                           (object ?object-designator)))")
                                 (9 "(exe:" "    (exe:perform (desig:an action")
                                 (12 "| + |" "                           (object ?object-designator)))))")))
  (expect (fboundp (btw "DRIVE-AND-PICK-UP-PLAN")) "not defined")
  ;; the plan it shows is the library's: its action designators resolve
  (expect (fboundp (find-symbol "DRIVE-TOWARDS-OBJECT-PLAN" "PR2-PP-PLANS")) "pr2-pp-plans has no drive-towards-object-plan"))

;;; Place objects

(replay-block 37 (:name "place the held bottle (object from the hand)"
                  :completions '((2 "(proj:" "(proj:with-projection-environment pr2-proj::pr2-bullet-projection-environment")
                                 (3 "| + |" "  (cpl:top-level")
                                 (4 "| + |" "    (exe:perform (desig:an action")))
  (expect (null (held-by :right)) "the right gripper still holds ~s" (held-by :right))
  (btr:simulate (world) 1)
  (expect (stable-p 'bottle-1) "bottle-1 is not stable after placing"))

(replay-block 38 (:name "pick the bottle up again"
                  :completions '((2 "(proj:" "(proj:with-projection-environment pr2-proj::pr2-bullet-projection-environment")
                                 (3 "| + |" "  (cpl:top-level")
                                 (4 "(let* ((?" "    (let* ((?bottle-desig (desig:an object")
                                 (6 "(?" "           (?perceived-bottle-desig (pr2-pp-plans::perceive ?bottle-desig)))")
                                 (7 "| + |" "      (pr2-pp-plans::drive-and-pick-up-plan ?perceived-bottle-desig :?arm :right))))")))
  (expect (equal '(bottle-1) (held-by :right)) "the right gripper holds ~s" (held-by :right)))

(replay-block 39 (:name "drive to the other table with a motion"
                  :completions '((1 "BTW-TUT> (proj:" "BTW-TUT> (proj:with-projection-environment pr2-proj::pr2-bullet-projection-environment")
                                 (2 "| + |" "           (cpl:top-level")
                                 (3 "| + |" "             (exe:perform")
                                 (4 "(let ((?pose (cl-tf:" "              (let ((?pose (cl-tf:make-pose-stamped")
                                 (5 "cram-tf:" "                            cram-tf:*fixed-frame* 0.0")
                                 (6 "(cl-transforms:" "                            (cl-transforms:make-3d-vector -0.15 2.0 0)")
                                 (7 "(cl-transforms:" "                            (cl-transforms:make-quaternion 0.0d0 0.0d0 -1.0d0 0.0d0))))")
                                 (8 "(desig:a motion (type going) (target (desig:a location (pose ?" "                (desig:a motion (type going) (target (desig:a location (pose ?pose))))))))")))
  (expect (near (xyz (btr:pose (robot-object))) '(-0.15 2.0 0) 1e-3) "the robot is at ~s" (xyz (btr:pose (robot-object))))
  (expect (equal '(bottle-1) (held-by :right)) "the bottle is no longer held"))

(replay-block 40 (:name "place the bottle at (-0.7 2.0 0.861667)"
                  :completions '((1 "BTW-TUT> (proj:" "BTW-TUT> (proj:with-projection-environment pr2-proj::pr2-bullet-projection-environment")
                                 (2 "| + |" "           (cpl:top-level")
                                 (3 "(let ((?" "             (let ((?drop-pose (cl-transforms-stamped:make-pose-stamped")
                                 (4 "\"" "                                \"map\" 0.0")
                                 (5 "(cl-transforms:" "                                (cl-transforms:make-3d-vector -0.7 2.0 0.861667d0)")
                                 (6 "(cl-transforms:" "                                (cl-transforms:make-identity-rotation))))")
                                 (7 "| + |" "               (exe:perform (desig:an action")
                                 (10 "(target (desig:a location (pose ?" "                                      (target (desig:a location (pose ?drop-pose))))))))")))
  (expect (null (held-by :right)) "still held")
  (btr:simulate (world) 1)
  (expect (near (subseq (xyz (btr:pose (obj 'bottle-1))) 0 2) '(-0.7 2.0) 0.03) "bottle-1 at ~s" (xyz (btr:pose (obj 'bottle-1))))
  (expect (on-island-p 'bottle-1) "bottle-1 is not on the island")
  (expect (stable-p 'bottle-1) "bottle-1 is not stable"))

;;; Construct plans

(replay-block 41 (:name "init-projection")
  (expect (robot-object) "no robot")
  (expect (null (obj 'bottle-1)) "bottle-1 survived"))

(replay-block 42 (:name "add the meshes")
  (expect (assoc :bottle btr:*mesh-files*) "no :bottle mesh"))

(replay-block 43 (:name "spawn two bottles"
                  :completions '((1 "BTW-TUT> (prolog:" "BTW-TUT> (prolog:prolog '(and (btr:bullet-world ?world)")
                                 (6 "(btr:" "                              (btr:simulate ?world 100)))")))
  (expect (and (obj 'bottle-1) (obj 'bottle-2)) "two bottles expected")
  (expect (on-island-p 'bottle-2) "bottle-2 is not on the island: ~s" (xyz (btr:pose (obj 'bottle-2)))))

(replay-block 44 (:name "the poses of the plan"
                  :completions '((3 "(cl-transforms-stamped:" "  (cl-transforms-stamped:make-pose-stamped")
                                 (4 "\"" "   \"map\" 0.0")
                                 (5 "| + |" "   (cl-transforms:make-3d-vector -2 -0.9d0 0.861667d0)")
                                 (6 "| + |" "   (cl-tf:make-quaternion 0.0d0 0.0d0 -1.0d0 0.0d0)))")
                                 (9 "(cl-transforms-stamped:" "  (cl-transforms-stamped:make-pose-stamped")
                                 (10 "\"" "   \"map\" 0.0")
                                 (11 "| + |" "   (cl-transforms:make-3d-vector -0.7 1.8 1.0d0)")
                                 (12 "| + |" "   (cl-transforms:make-identity-rotation)))")
                                 (15 "(cl-tf:" "  (cl-tf:make-pose-stamped")
                                 (16 "\"" "   \"map\" 0.0")
                                 (17 "| + |" "   (cl-tf:make-3d-vector -0.15 2.0 0)")
                                 (18 "| + |" "   (cl-tf:make-quaternion 0.0d0 0.0d0 -1.0d0 0.0d0)))")
                                 (21 "(cl-transforms-stamped:" "  (cl-transforms-stamped:make-pose-stamped")
                                 (22 "\"" "   \"map\" 0.0")
                                 (23 "| + |" "   (cl-transforms:make-3d-vector -1.8547d0 -0.381d0 0.0d0)")
                                 (24 "| + |" "   (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) (/ pi -2))))")))
  ;; the literals below are single floats: compare to 1e-6 (1e-9 was tighter than they are exact)
  (expect (near (xyz (symbol-value (btw "*POSE-COUNTER*"))) '(-1.8547 -0.381 0) 1e-6) "*pose-counter* is at ~s"
          (xyz (symbol-value (btw "*POSE-COUNTER*"))))
  (expect (near (xyz (symbol-value (btw "*POSE-BOTTLE-2*"))) '(-0.7 1.8 1.0) 1e-6) "*pose-bottle-2*"))

;; The page shows this block without a prompt: the reader is still in BTW-TUT (block 1's
;; in-package), so it is replayed there (not in CL-USER, where its functions would not be the
;; ones block 46's plan calls).
(replay-block 45 (:name "the plan's small steps" :package "CRAM-BULLET-WORLD-TUTORIAL"
                  :completions '((2 "(unless (assoc :bottle btr::" "  (unless (assoc :bottle btr::*mesh-files*)")
                                 (4 "(prolog:" "  (prolog:prolog '(and (btr:bullet-world ?world)")
                                 (9 "(btr:" "              (btr:simulate ?world 100))))")
                                 (11 "(defun move-arm-out-of-sight (&key (arm '" "(defun move-arm-out-of-sight (&key (arm '(:left :right)))")
                                 (14 "(exe:" "  (exe:perform")
                                 (15 "(let ((?" "   (let ((?left-configuration-to-go pr2-pp-plans::*pr2-left-arm-out-of-sight-joint-positions*)")
                                 (16 "| + |" "         (?right-configuration-to-go pr2-pp-plans::*pr2-right-arm-out-of-sight-joint-positions*))")
                                 (17 "| + |" "     (desig:a motion")
                                 (19 "(left-configuration ?" "              (left-configuration ?left-configuration-to-go)")
                                 (20 "(right-configuration ?" "              (right-configuration ?right-configuration-to-go)))))")
                                 (22 "(defun navigate-to (?" "(defun navigate-to (?navigation-goal)")
                                 (23 "(exe:" "  (exe:perform (desig:a motion")
                                 (25 "(target (desig:a location (pose ?" "                        (target (desig:a location (pose ?navigation-goal))))))")
                                 (27 "(defun look-at (?" "(defun look-at (?point-of-interest)")
                                 (28 "(exe:" "  (exe:perform (desig:a motion")
                                 (30 "(target (desig:a location (pose ?" "                        (target (desig:a location (pose ?point-of-interest))))))")
                                 (33 "(let* ((?" "  (let* ((?bottle-desig (desig:an object")
                                 (35 "| + |" "         (?perceived-bottle-desig (exe:perform")
                                 (36 "| + |" "                                   (desig:a motion")
                                 (38 "(object ?" "                                            (object ?bottle-desig)))))")
                                 (39 "?" "    ?perceived-bottle-desig))")
                                 (41 "(defun pick-up (?" "(defun pick-up (?object-designator &optional (?arm :right))")
                                 (42 "(exe:" "  (exe:perform (desig:an action")
                                 (45 "| + |" "                         (object ?object-designator))))")
                                 (48 "(exe:" "  (exe:perform (desig:an action")
                                 (51 "| + |" "                         (target (desig:a location (pose ?pose))))))")
                                 (53 "(defun move-to-reach (?" "(defun move-to-reach (?object-designator &optional (arm :right))")
                                 (54 "(pr2-pp-plans::" "  (pr2-pp-plans::drive-towards-object-plan ?object-designator :?arm arm))")))
  (dolist (f '("SPAWN-TWO-BOTTLES" "MOVE-ARM-OUT-OF-SIGHT" "NAVIGATE-TO" "LOOK-AT" "GET-PERCEIVED-BOTTLE-DESIG"
               "PICK-UP" "PLACE-DOWN" "MOVE-TO-REACH"))
    (expect (fboundp (btw f)) "~a is not defined" f))
  ;; the definitions are the page's: its place-down takes (?pose ?arm)
  (expect (equal '("?POSE" "?ARM") (mapcar #'string (sb-kernel:%fun-lambda-list (fdefinition (btw "PLACE-DOWN")))))
          "place-down is not the page's: ~s" (sb-kernel:%fun-lambda-list (fdefinition (btw "PLACE-DOWN")))))

(replay-block 46 (:name "switch two bottles"
                  :completions '((4 "(proj:" "  (proj:with-projection-environment pr2-proj::pr2-bullet-projection-environment")
                                 (5 "(cpl:" "    (cpl:top-level")
                                 (7 "(let ((?" "      (let ((?navigation-goal *pose-counter*)")
                                 (8 "(?ptu-goal pr2-pp-plans::" "            (?ptu-goal pr2-pp-plans::*meal-table-right-base-look-pose*))")
                                 (11 "(exe:" "          (exe:perform")
                                 (12 "| + |" "           (desig:a motion (type moving-torso) (joint-angle 0.3)))")
                                 (14 "(navigate-to ?" "          (navigate-to ?navigation-goal))")
                                 (15 "(look-at ?" "        (look-at ?ptu-goal))")
                                 (17 "(let* ((?" "      (let* ((?perceived-bottle-desig (get-perceived-bottle-desig)))")
                                 (18 "(move-to-reach ?" "        (move-to-reach ?perceived-bottle-desig :right)")
                                 (19 "(pick-up ?" "        (pick-up ?perceived-bottle-desig :right))")
                                 (25 "(let* ((?" "      (let* ((?perceived-bottle-desig (get-perceived-bottle-desig)))")
                                 (26 "(move-to-reach ?" "        (move-to-reach ?perceived-bottle-desig :left)")
                                 (27 "(pick-up ?" "        (pick-up ?perceived-bottle-desig :left))")
                                 (31 "(let ((?" "      (let ((?drop-pose *pose-bottle-2*))")
                                 (36 "(let ((?" "      (let ((?navigation-goal *pose-counter*))")
                                 (37 "| + |" "        (navigate-to ?navigation-goal))")
                                 (39 "(let ((?" "      (let ((?drop-pose *pose-bottle-1*))")))
  (expect (fboundp (btw "TEST-SWITCH-TWO-BOTTLES")) "not defined")
  ;; "Each time you run test-switch-two-bottles": run it on a fresh world
  (funcall (btw "INIT-PROJECTION"))
  (funcall (btw "TEST-SWITCH-TWO-BOTTLES"))
  (btr:simulate (world) 1)
  (expect (null (held-by :left)) "the left gripper still holds ~s" (held-by :left))
  (expect (null (held-by :right)) "the right gripper still holds ~s" (held-by :right))
  (expect (on-island-p 'bottle-1) "bottle-1 is not on the island: ~s" (xyz (btr:pose (obj 'bottle-1))))
  (expect (near (subseq (xyz (btr:pose (obj 'bottle-2))) 0 2) '(-2 -0.9) 0.05) "bottle-2 is at ~s" (xyz (btr:pose (obj 'bottle-2))))
  (expect (and (stable-p 'bottle-1) (stable-p 'bottle-2)) "the bottles are not stable"))

;;; The page's last section (`Light-weight simulation': find the red mug in projection, the
;;; pancake demo) is inside `<html><!-- ... -->': readers never see it, and DEFINE-SEED above
;;; leaves its two blocks out of N. Check that the detector left out exactly those.

(let* ((all (code-blocks (seed-lines *seed*)))
       (hidden (remove-if-not (lambda (b) (html-commented-p b (seed-lines *seed*))) all)))
  (unless (and (= 2 (length hidden))
               (search "with-projection-environment" (format nil "~{~a~}" (mapcar #'cdr (first hidden))))
               (search "execute-demo" (format nil "~{~a~}" (mapcar #'cdr (second hidden)))))
    (error "seed 001: the commented-out blocks are not the red-mug and pancake-demo blocks: ~s" hidden)))

(finish-seed)
