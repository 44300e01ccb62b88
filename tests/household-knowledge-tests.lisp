;;;; Household object knowledge: types, efforts and openings, CRAM's grasps with their
;;;; pregrasps and lifts per location type, carry configurations, likely locations and
;;;; destinations per context, the spoon mesh.

(defpackage :cram-household-tests
  (:use :cl :fiveam))

(in-package :cram-household-tests)

(def-suite household :in cram-plans-tests:all
  :description "Household object knowledge and location designators.")

(in-suite household)

(defvar *household-world* nil "The kitchen belief state the tests copy, built once.")

(defun kitchen () (btr:object btr:*current-bullet-world* :iai-kitchen))

(defmacro with-household-kitchen (() &body body)
  "Run BODY in a copy of the kitchen with the PR2 (BTW-TUT:INIT-PROJECTION's world)."
  `(progn
     (unless *household-world*
       (btw-tut:init-projection)
       (setf *household-world* (btr:copy-world btr:*current-bullet-world*)))
     (let ((btr:*current-bullet-world* (btr:copy-world *household-world*))
           (rob-int:*robot-name* :pr2)
           (costmap:*costmap-random-state* (sb-ext:seed-random-state 7)))
       (unwind-protect (progn ,@body)
         (btr:destroy-world btr:*current-bullet-world*)))))

(defun spawn (name mesh pose)
  (btr:add-object btr:*current-bullet-world* :mesh name pose :mesh mesh :mass 0.2 :types (list mesh)))

(defun xyz (thing)
  (let ((o (if (typep thing 'cl-transforms:pose) (cl-transforms:origin thing) thing)))
    (list (cl-transforms:x o) (cl-transforms:y o) (cl-transforms:z o))))

(defun dist-xy (p q)
  (sqrt (+ (expt (- (first p) (first q)) 2) (expt (- (second p) (second q)) 2))))

(defun yaw-of (pose)
  (let ((x (cl-transforms:rotate (cl-transforms:orientation pose) (cl-transforms:make-3d-vector 1 0 0))))
    (atan (cl-transforms:y x) (cl-transforms:x x))))

(defun close-vectors-p (v list &optional (eps 1d-6))
  (every (lambda (a b) (< (abs (- a b)) eps)) (xyz v) list))

(test household-types-efforts-openings
  (is-true (man-int:object-type-subtype-p :household-item :spoon))
  (is-true (man-int:object-type-subtype-p :cutlery :spoon))
  (is-true (man-int:object-type-subtype-p :kitchen-item :bowl))
  (is-true (man-int:object-type-subtype-p :cup :mug))
  (is-true (man-int:object-type-subtype-p :cereal :breakfast-cereal))
  (is-false (man-int:object-type-subtype-p :cup :bowl))
  (is (= 50 (man-int:get-object-type-gripping-effort :bowl)))
  (is (= 20 (man-int:get-object-type-gripping-effort :milk)))
  (is (= 45 (man-int:get-object-type-gripping-effort :breakfast-cereal)))
  (is (= 0.1 (man-int:get-object-type-gripper-opening :cup)))
  (is (= 0.05 (man-int:get-object-type-gripper-opening :spoon)))
  (is (= 0.02 (man-int:get-object-type-gripper-opening :plate)))
  (is (member :spoon (objects:household-object-types)))
  (is (every (lambda (type) (man-int:object-type-subtype-p :household-item type))
             (objects:household-object-types))
      "only household items")
  (is-false (man-int:object-rotationally-symmetric-p :bowl))
  (is-true (man-int:object-rotationally-symmetric-p :bottle) "the bottle keeps its knowledge"))

(test cup-and-cereal-grasps-as-cram
  (let ((top (man-int:get-object-type-to-gripper-transform :cup nil :left :top)))
    (is (close-vectors-p (cl-transforms:translation top) '(-0.05 0 0.04)))
    ;; rotation ZY (CRAM's z-forward gripper frame): the tool frame's x axis, forward between
    ;; the fingers, along the object's -z
    (is (close-vectors-p (cl-transforms:rotate (cl-transforms:rotation top) (cl-transforms:make-3d-vector 1 0 0))
                         '(0 0 -1)))
    (let ((pregrasps (man-int:get-object-type-to-gripper-pregrasp-transforms :cup nil :left :top)))
      (is (close-vectors-p (cl-transforms:translation (first pregrasps)) '(-0.05 0 0.11)))
      (is (close-vectors-p (cl-transforms:translation (second pregrasps)) '(-0.05 0 0.11)))))
  (let ((pregrasps (man-int:get-object-type-to-gripper-pregrasp-transforms :cup nil :right :left-side)))
    (is (close-vectors-p (cl-transforms:translation (first pregrasps)) '(0 0.13 0.08)))
    (is (close-vectors-p (cl-transforms:translation (second pregrasps)) '(0 0.13 0.01))))
  (is (equal '(:top :top2 :left-side :right-side :back :front) (man-int:object-type-grasps :mug))
      "mugs are cups")
  (let ((flipped (man-int:get-object-type-to-gripper-transform :breakfast-cereal nil :left :front-flipped)))
    ;; XZ2 rows (0 0 -1) (1 0 0) (0 -1 0): approaching along the object's -x (from the front,
    ;; as XZ), the fingers' plane turned about the approach: the tool's y axis along +y (XZ: -y)
    (is (close-vectors-p (cl-transforms:rotate (cl-transforms:rotation flipped) (cl-transforms:make-3d-vector 1 0 0))
                         '(-1 0 0)))
    (is (close-vectors-p (cl-transforms:rotate (cl-transforms:rotation flipped) (cl-transforms:make-3d-vector 0 1 0))
                         '(0 1 0)))
    (is (close-vectors-p (cl-transforms:rotate (cl-transforms:rotation
                                                (man-int:get-object-type-to-gripper-transform
                                                 :breakfast-cereal nil :left :front))
                                               (cl-transforms:make-3d-vector 0 1 0))
                         '(0 -1 0))))
  (destructuring-bind (one two) (man-int:get-object-type-lift-offsets :cereal :front)
    (is (close-vectors-p one '(0 0 0.1d0)))
    (is (close-vectors-p two '(0 0 0.2d0))))
  (destructuring-bind (one two) (man-int:get-object-type-lift-offsets :breakfast-cereal :back :shelf)
    (is (close-vectors-p one '(-0.015 0 0.06)) "out of a shelf: lifted a little")
    (is (close-vectors-p two '(-0.415 0 0.12)) "then pulled 0.4 m out")))

(test bowl-in-a-drawer-uses-its-own-pregrasp
  (let ((in-drawer (desig:an object (type bowl)
                             (location (desig:a location (in (desig:an object (type drawer)
                                                                       (urdf-name sink-area-left-middle-drawer-main)
                                                                       (part-of iai-kitchen))))))))
    (is (eq :drawer (man-int:get-object-location-type in-drawer)))
    (is (null (man-int:get-object-location-type (desig:an object (type bowl)))))
    (let ((drawer (man-int:get-action-trajectory :picking-up :left :top :bowl (cl-transforms:make-identity-pose)
                                                 :location-type :drawer))
          (table (man-int:get-action-trajectory :picking-up :left :top :bowl (cl-transforms:make-identity-pose))))
      (is (close-vectors-p (cl-transforms:origin (first (man-int:get-traj-poses-by-label drawer :reaching)))
                           '(-0.08 0 0.22)))
      (is (close-vectors-p (cl-transforms:origin (second (man-int:get-traj-poses-by-label drawer :lifting)))
                           '(-0.08 0 0.42)))
      (is (close-vectors-p (cl-transforms:origin (first (man-int:get-traj-poses-by-label table :reaching)))
                           '(-0.08 0 0.09))))
    (is-true (man-int:grasp-location-variant-p :spoon :top :shelf) "cutlery on a shelf")
    (is-false (man-int:grasp-location-variant-p :cup :top :drawer))))

(test bottle-grasps-unchanged
  (let ((pregrasps (man-int:get-object-type-to-gripper-pregrasp-transforms :bottle nil :left :left-side)))
    (is (close-vectors-p (cl-transforms:translation (first pregrasps)) '(0 0.17 0.075) 1d-6))
    (is (close-vectors-p (cl-transforms:translation (second pregrasps)) '(0 0.17 0.005) 1d-6)))
  (destructuring-bind (one two) (man-int:get-object-type-to-gripper-lift-offsets :bottle :left-side)
    (is (< (abs (- one 0.07)) 1d-6) "two lifts of 0.07 m")
    (is (< (abs (- two 0.14)) 1d-6))))

(test carry-configurations
  (is (eq :carry-top (man-int:get-object-type-carry-config :bowl :top-left)))
  (is (eq :carry-top (man-int:get-object-type-carry-config :cup :top2)))
  (is (eq :carry (man-int:get-object-type-carry-config :cup :front)))
  (is (eq :carry-top (man-int:get-object-type-carry-config :breakfast-cereal :top)))
  (is (eq :carry (man-int:get-object-type-carry-config :milk :front)))
  (let ((left (rob-int:get-robot-joint-states :pr2 :arm :left :carry-top)))
    (is (= 7 (length left)))
    (is (= 1.0252138d0 (second (assoc "l_shoulder_pan_joint" left :test #'string=)))))
  (is (= -1.9747830d0 (second (assoc "r_wrist_roll_joint"
                                     (rob-int:get-robot-joint-states :pr2 :arm :right :carry-top)
                                     :test #'string=)))))

(defun reference-of (location key)
  (desig:desig-prop-value location key))

(test likely-locations-and-destinations-per-context
  (let ((bowl (man-int:get-object-likely-location :bowl :iai-kitchen nil :table-setting)))
    (is (eq :sink-area-left-middle-drawer-main (desig:desig-prop-value (reference-of bowl :in) :urdf-name)))
    (is (eq :back (desig:desig-prop-value bowl :side))))
  (let ((cereal (man-int:get-object-likely-location :breakfast-cereal :iai-kitchen nil :table-setting)))
    (is (eq :topmost (desig:desig-prop-value (reference-of cereal :in) :level)))
    (is (eq :breakfast-cereal (desig:desig-prop-value (desig:desig-prop-value cereal :for) :type))))
  (let ((spoon (man-int:get-object-destination :spoon :iai-kitchen nil :table-setting)))
    (is (= 0.9 (desig:desig-prop-value spoon :threshold)))
    (is (eq :bowl (desig:desig-prop-value (desig:desig-prop-value spoon :right-of) :type))))
  (is (equal '(:dish-washer-drawer-center)
             (desig:desig-prop-value (man-int:get-object-destination :spoon :iai-kitchen nil :table-cleaning)
                                     :attachments)))
  (is (eq :sink-area-sink
          (desig:desig-prop-value (reference-of (man-int:get-object-destination :mug :iai-kitchen nil :table-cleaning)
                                                :above)
                                  :urdf-name))
      "mugs go to the sink, not the dishwasher")
  (is (eq :dining-area-jokkmokk-table-main
          (desig:desig-prop-value (reference-of (man-int:get-object-likely-location :cup :iai-kitchen nil :table-cleaning)
                                                :on)
                                  :urdf-name)))
  (is (eq :oven-area-area-right-drawer-main
          (desig:desig-prop-value (reference-of (man-int:get-object-destination :breakfast-cereal :iai-kitchen nil
                                                                                :table-cleaning)
                                                :in)
                                  :urdf-name))
      "cereal goes back where it came from")
  (flet ((message (form) (handler-case (progn (funcall form) "no error") (error (e) (princ-to-string e)))))
    (let ((m (message (lambda () (man-int:get-object-destination :somat :iai-kitchen nil :table-setting)))))
      (is (search ":SOMAT" m))
      (is (search ":BOWL" m) "lists the types known in that context: ~a" m))
    (is (search "\"bowl\"" (message (lambda () (man-int:get-object-destination "bowl" :iai-kitchen nil :table-setting)))))
    (is (search ":DINNER" (message (lambda () (man-int:get-object-likely-location :bowl :iai-kitchen nil :dinner)))))))

(defun stl-bounds (file)
  "(values min max) corners, as (x y z) lists, of the vertices of the binary STL FILE."
  (with-open-file (in file :element-type '(unsigned-byte 8))
    (flet ((u32 () (let ((v 0)) (dotimes (i 4 v) (setf v (logior v (ash (read-byte in) (* 8 i))))))))
      (file-position in 80)
      (let ((lo (list 1d9 1d9 1d9)) (hi (list -1d9 -1d9 -1d9)))
        (dotimes (k (u32))
          (dotimes (i 3) (u32))
          (dotimes (v 3)
            (dotimes (i 3)
              (let ((x (sb-kernel:make-single-float (let ((b (u32))) (if (>= b (expt 2 31)) (- b (expt 2 32)) b)))))
                (setf (nth i lo) (min (nth i lo) x) (nth i hi) (max (nth i hi) x)))))
          (read-byte in) (read-byte in))
        (values lo hi)))))

(test spoon-mesh-has-crams-size
  (multiple-value-bind (lo hi) (stl-bounds (asdf:system-relative-pathname "cram-plans" "resources/meshes/spoon.stl"))
    (is (every (lambda (a b) (< (abs (- a b)) 1d-6)) (mapcar #'- hi lo) '(0.2167 0.0463 0.0189))
        "0.2167 x 0.0463 x 0.0189 m")
    (is (every (lambda (a b) (< (abs (- a b)) 1d-6)) lo '(-0.1105 -0.0233 -0.0063))
        "its box's low corner from the origin"))
  (with-household-kitchen ()
    (is (typep (spawn :spoon-1 :spoon '((0 0 2) (0 0 0 1))) 'btr:item) "a :spoon mesh object")))

(defun pregrasp-height (?object)
  "How far above the grasp pose the first pregrasp pose lies when picking up ?OBJECT from the
top with the left arm."
  (let* ((groundings (pp-plans::picking-up-groundings
                      (desig:an action (type picking-up) (arm left) (grasp top) (object ?object))))
         (trajectory (desig:desig-prop-value (second (first groundings)) :trajectory)))
    (flet ((z (label) (cl-transforms:z (cl-transforms:origin
                                        (first (man-int:get-traj-poses-by-label trajectory label))))))
      (- (z :reaching) (z :grasping)))))

(test picking-up-a-bowl-from-a-drawer-reaches-from-higher
  (with-household-kitchen ()
    (spawn :bowl-1 :bowl '((1.2 0.95 0.47) (0 0 0 1)))
    (let ((in-drawer (desig:an object (type bowl) (name bowl-1)
                               (location (desig:a location
                                                  (in (desig:an object (type drawer)
                                                                (urdf-name sink-area-left-middle-drawer-main)
                                                                (part-of iai-kitchen))))))))
      (is (< (abs (- (pregrasp-height in-drawer) 0.2)) 1d-6) "0.2 m above the grasp in a drawer")
      (is (< (abs (- (pregrasp-height (desig:an object (type bowl) (name bowl-1))) 0.07)) 1d-6)
          "0.07 m elsewhere"))))
