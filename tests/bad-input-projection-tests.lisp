;;;; The bad-input suite, projection cases: belief state (BTR), URDF, the simulated robot and its
;;;; motions, costmaps. The table and its runner are in bad-input-tests.lisp.

(in-package :cram-plans-tests.bad-input)

(defvar *resources* (asdf:system-relative-pathname "cram-plans/cram-urdf-projection" "resources/"))
(defvar *robots* (asdf:system-relative-pathname "cram-plans/cram-urdf-projection" "robots/"))

(defun read-file (relative base) (uiop:read-file-string (merge-pathnames relative base)))

(defun pose0 () '((0 0 0) (0 0 0 1)))

(defun small-world ()
  "A new current world with a floor, a box BOX-1 and a bottle BOTTLE-1."
  (btr:register-ros-package "cram_plans_resources" (namestring *resources*))
  (btr:add-objects-to-mesh-list "cram_plans_resources" :directory "meshes")
  (let ((w (make-instance 'btr:bt-reasoning-world)))
    (setf btr:*current-bullet-world* w)
    (btr:add-object w :static-plane :floor (pose0) :normal '(0 0 1) :constant 0)
    (btr:add-object w :box 'box-1 '((1 0 0.5) (0 0 0 1)) :size '(0.2 0.2 0.2) :mass 1)
    (btr:add-object w :mesh 'bottle-1 '((0 1 0.1) (0 0 0 1)) :mass 0.2 :mesh :bottle
                                                            :types '(:bottle))
    w))

(defvar *pr2-urdf* nil)
(defun pr2-urdf () (or *pr2-urdf* (setf *pr2-urdf* (read-file "pr2/pr2.urdf" *robots*))))
(defvar *kitchen-urdf* nil)
(defun kitchen-urdf () (or *kitchen-urdf* (setf *kitchen-urdf* (read-file "iai_kitchen.urdf" *resources*))))

(defun robot-world ()
  "A new current world with floor, kitchen, the PR2 at the origin and BOTTLE-1 on the table."
  (let ((w (small-world)))
    (rob-int:set-robot-name :pr2)
    (btr:add-object w :urdf :iai-kitchen (pose0) :urdf (kitchen-urdf)
                                                 :collision-group :static-filter
                                                 :collision-mask '(:default-filter :character-filter))
    (btr:add-object w :urdf :pr2 (pose0) :urdf (pr2-urdf))
    w))

(defmacro in-small-world (&body body)
  `(let ((btr:*current-bullet-world* btr:*current-bullet-world*))
     (let ((w (small-world)))
       (declare (ignorable w))
       ,@body)))

(defmacro in-robot-world (&body body)
  `(let ((btr:*current-bullet-world* btr:*current-bullet-world*)
         (rob-int:*robot-name* rob-int:*robot-name*))
     (let ((w (robot-world)))
       (declare (ignorable w))
       ,@body)))

(defmacro simulated (&body body)
  "BODY in the robot world, with the simulated robot."
  `(in-robot-world (urdf-proj:with-simulated-robot ,@body)))

(defun ps (frame x y z)
  (cl-transforms-stamped:make-pose-stamped frame 0 (cl-transforms:make-3d-vector x y z)
                                           (cl-transforms:make-identity-rotation)))

(defparameter *tiny-urdf*
  "<robot name=\"tiny\">
  <link name=\"base\"><collision><geometry><box size=\"0.1 0.1 0.1\"/></geometry></collision></link>
  <link name=\"arm\"><collision><geometry><box size=\"0.1 0.1 0.1\"/></geometry></collision></link>
  <joint name=\"j1\" type=\"revolute\"><parent link=\"base\"/><child link=\"arm\"/>
    <axis xyz=\"0 0 1\"/><limit lower=\"~a\" upper=\"~a\" effort=\"1\" velocity=\"1\"/></joint>
</robot>")

(defun tiny-urdf (&optional (lower -1) (upper 1)) (format nil *tiny-urdf* lower upper))

(defparameter *cycle-urdf*
  "<robot name=\"cyclic\">
  <link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>
  <joint name=\"ab\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint>
  <joint name=\"bc\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>
  <joint name=\"ca\" type=\"fixed\"><parent link=\"c\"/><child link=\"a\"/></joint>
</robot>")

;;; ---- belief state -----------------------------------------------------------------------

(defcases :btr
  (simulate-nan :error (in-small-world (btr:simulate w (nan))) :match "NaN")
  (simulate-huge :error (in-small-world (btr:simulate w 1d300)) :match "1.0d300")
  (simulate-negative :error (in-small-world (btr:simulate w -1)) :match "-1")
  (simulate-dt-zero :error (in-small-world (btr:simulate w 1 0)) :match "0")
  (simulate-dt-nan :error (in-small-world (btr:simulate w 1 (nan))) :match "NaN")
  (simulate-dt-tiny :error (in-small-world (btr:simulate w 1 1d-300)) :match "1.0d-300")
  (simulate-not-a-world :error (btr:simulate 42 1) :match "42")
  (simulate-through-prolog-nan :error
   (in-small-world (query `(and (btr:bullet-world ?w) (btr:simulate ?w ,(nan))))) :match "NaN")
  (copied-world-number :error (btr:with-copied-world (42) 1) :match "42")
  (copy-world-string :error (btr:copy-world "world") :match "\"world\"")
  (add-object-odd-keys :error (in-small-world (btr:add-object w :box 'b (pose0) :size))
   :match ":SIZE")
  (add-object-non-keyword :error (in-small-world (btr:add-object w :box 'b (pose0) 42 1))
   :match "42")
  (add-object-not-a-world :error (btr:add-object 42 :box 'b (pose0)) :match "42")
  (add-object-unknown-kind :error (in-small-world (btr:add-object w :tetrahedron 'b (pose0)))
   :match ":TETRAHEDRON")
  (add-object-unknown-key :error (in-small-world (btr:add-object w :box 'b (pose0) :colour '(1 0 0)))
   :match ":COLOUR")
  (add-object-size-huge :error (in-small-world (btr:add-object w :box 'b (pose0) :size '(1d200 1 1)))
   :match "1.0d200")
  (add-object-mass-huge :error (in-small-world (btr:add-object w :box 'b (pose0) :mass 1d300))
   :match "1.0d300")
  (add-object-mass-negative :error (in-small-world (btr:add-object w :box 'b (pose0) :mass -1))
   :match "-1")
  (add-object-size-string :error (in-small-world (btr:add-object w :box 'b (pose0) :size '("a" 1 1)))
   :match "\"a\"")
  (add-object-size-short :error (in-small-world (btr:add-object w :box 'b (pose0) :size '(1 1)))
   :match "(1 1)")
  (add-object-pose-nan :error (in-small-world (btr:add-object w :box 'b `((,(nan) 0 0) (0 0 0 1))))
   :match "NaN")
  (add-object-pose-huge :error (in-small-world (btr:add-object w :box 'b '((1d300 0 0) (0 0 0 1))))
   :match "1.0d300")
  (add-object-pose-number :error (in-small-world (btr:add-object w :box 'b 42)) :match "42")
  (add-object-zero-quaternion :error (in-small-world (btr:add-object w :box 'b '((0 0 0) (0 0 0 0))))
   :match "0")
  (add-object-radius-negative :error (in-small-world (btr:add-object w :sphere 'b (pose0) :radius -1))
   :match "-1")
  (add-object-radius-huge :error (in-small-world (btr:add-object w :sphere 'b (pose0) :radius 1d200))
   :match "1.0d200")
  (add-object-plane-zero-normal :error
   (in-small-world (btr:add-object w :static-plane 'p (pose0) :normal '(0 0 0))) :match "(0 0 0)")
  (add-object-color-string :error (in-small-world (btr:add-object w :box 'b (pose0) :color "red"))
   :match "\"red\"")
  (add-object-bad-collision-group :error
   (in-small-world (btr:add-object w :box 'b (pose0) :collision-group :bad-input-filter))
   :match ":BAD-INPUT-FILTER")
  (add-object-unknown-mesh :error (in-small-world (btr:add-object w :mesh 'b (pose0) :mesh :bad-input-mesh))
   :match ":BAD-INPUT-MESH")
  (add-object-types-string :error
   (in-small-world (btr:add-object w :box 'b (pose0) :types "bottle"))
   :match "\"bottle\"")
  (add-object-types-strings-in-list :accepts
   (in-small-world (btr:add-object w :box 'b (pose0) :types '("bottle"))
                   (assert (equal '(:bottle) (btr:item-types (btr:object w 'b))))))
  (add-object-types-number :error (in-small-world (btr:add-object w :box 'b (pose0) :types 42))
   :match "42")
  (add-object-urdf-number :error (in-small-world (btr:add-object w :urdf 'r (pose0) :urdf 42))
   :match "42")
  (removed-object-pose :error
   (in-small-world (let ((o (btr:object w 'box-1))) (btr:remove-object w 'box-1) (btr:pose o)))
   :match "BOX-1")
  (removed-object-set-pose :error
   (in-small-world (let ((o (btr:object w 'box-1))) (btr:remove-object w 'box-1)
                     (setf (btr:pose o) (cl-transforms:make-identity-pose))))
   :match "BOX-1")
  (removed-object-aabb :error
   (in-small-world (let ((o (btr:object w 'box-1))) (btr:remove-object w 'box-1) (btr:aabb o)))
   :match "BOX-1")
  (destroyed-world-simulate :error
   (in-small-world (btr:destroy-world w) (btr:simulate w 1)) :match "destroyed")
  (destroyed-world-add :error
   (in-small-world (btr:destroy-world w) (btr:add-object w :box 'b (pose0))) :match "destroyed")
  (destroyed-world-pose :error
   (in-small-world (btr:destroy-world w) (btr:pose (btr:object w 'box-1))) :match "BOX-1")
  (destroyed-world-copy :error (in-small-world (btr:destroy-world w) (btr:copy-world w))
   :match "destroyed")
  (remove-unknown-object :error (in-small-world (btr:remove-object w 'bad-input-nothing))
   :match "BAD-INPUT-NOTHING")
  (set-pose-number :error (in-small-world (setf (btr:pose (btr:object w 'box-1)) 42)) :match "42")
  (aabb-number :error (btr:aabb 42) :match "42")
  (pose-of-symbol :error (btr:pose 'box-1) :match "BOX-1")
  (object-pose-unknown :error (in-small-world (btr:object-pose 'bad-input-nothing))
   :match "BAD-INPUT-NOTHING")
  (robot-state-on-box :error
   (in-small-world (btr:set-robot-state-from-joints '(("j" 1)) (btr:object w 'box-1)))
   :match "BOX-1")
  (joint-state-on-box :error (in-small-world (btr:joint-state (btr:object w 'box-1) "j"))
   :match "BOX-1")
  (robot-state-nan :error
   (in-robot-world (btr:set-robot-state-from-joints `(("torso_lift_joint" ,(nan))) (btr:object w :pr2)))
   :match "NaN")
  (robot-state-unknown-joint :error
   (in-robot-world (btr:set-robot-state-from-joints '(("bad_input_joint" 0)) (btr:object w :pr2)))
   :match "bad_input_joint")
  (robot-state-beyond-limit :warns
   (in-robot-world (btr:set-robot-state-from-joints '(("torso_lift_joint" 5)) (btr:object w :pr2))))
  (link-pose-unknown :error (in-robot-world (btr:link-pose (btr:object w :pr2) "bad_input_link"))
   :match "bad_input_link")
  (attach-number :error (in-small-world (btr:attach-object 42 (btr:object w 'box-1))) :match "42")
  (stable-unknown :error (in-small-world (btr:stable-p w 'bad-input-nothing)) :match "BAD-INPUT-NOTHING")
  (restore-state-number :error (in-small-world (btr:restore-world-state 42 w)) :match "42")
  (prolog-object-pose-unknown :error
   (in-small-world (query '(and (btr:bullet-world ?w)
                            (btr:assert ?w (btr:object-pose bad-input-nothing ((0 0 0) (0 0 0 1)))))))
   :match "BAD-INPUT-NOTHING")
  (prolog-object-pose-bad-pose :error
   (in-small-world (query '(and (btr:bullet-world ?w) (btr:assert ?w (btr:object-pose box-1 42)))))
   :match "42")
  (prolog-assert-bad-pose :error
   (in-small-world (query '(and (btr:bullet-world ?w) (btr:assert (btr:object ?w :box b2 42)))))
   :match "42")
  (prolog-assert-unknown-kind :error
   (in-small-world (query '(and (btr:bullet-world ?w)
                            (btr:assert (btr:object ?w :tetrahedron b2 ((0 0 0) (0 0 0 1)))))))
   :match ":TETRAHEDRON")
  (prolog-assert-odd-keys :error
   (in-small-world (query '(and (btr:bullet-world ?w)
                            (btr:assert (btr:object ?w :box b2 ((0 0 0) (0 0 0 1)) :size)))))
   :match ":SIZE")
  (prolog-joint-state-nan :error
   (in-robot-world (query `(and (btr:bullet-world ?w)
                            (btr:assert ?w (btr:joint-state :pr2 (("torso_lift_joint" ,(nan))))))))
   :match "NaN")
  (prolog-joint-state-beyond-limit :warns
   (in-robot-world (query '(and (btr:bullet-world ?w)
                            (btr:assert ?w (btr:joint-state :pr2 (("torso_lift_joint" 5))))))))
  (prolog-joint-state-unknown-robot :error
   (in-small-world (query '(and (btr:bullet-world ?w)
                            (btr:assert ?w (btr:joint-state bad-input-robot (("j" 0)))))))
   :match "BAD-INPUT-ROBOT")
  (prolog-item-type-unknown :fails
   (in-small-world (query '(and (btr:bullet-world ?w) (btr:item-type ?w bad-input-nothing ?t)))))
  (prolog-item-type-removed :fails
   (in-small-world (btr:remove-object w 'bottle-1)
                   (query '(and (btr:bullet-world ?w) (btr:item-type ?w bottle-1 ?t)))))
  (prolog-item-type-racing-remove :accepts
   (in-small-world
     (let ((stop nil))
       (let ((remover (sb-thread:make-thread
                       (lambda ()
                         (loop until stop
                               do (ignore-errors (btr:remove-object w 'bottle-1))
                                  (ignore-errors
                                   (btr:add-object w :mesh 'bottle-1 '((0 1 0.1) (0 0 0 1))
                                                   :mesh :bottle :types '(:bottle))))))))
         (unwind-protect
              (dotimes (i 300)
                (query '(and (btr:bullet-world ?w) (btr:item-type ?w ?o ?t))))
           (setf stop t)
           (sb-thread:join-thread remover :default nil))))))
  (prolog-contact-number :fails
   (in-small-world (query '(and (btr:bullet-world ?w) (btr:contact ?w 42 ?o)))))
  (prolog-with-copied-world-number :error (query '(btr:with-copied-world 42 (prolog:true)))
   :match "42")
  (prolog-simulate-string :error
   (in-small-world (query '(and (btr:bullet-world ?w) (btr:simulate ?w "one"))))
   :match "\"one\""))

;;; ---- URDF -------------------------------------------------------------------------------

(defcases :urdf
  (urdf-empty-string :error (cl-urdf:parse-urdf "") :match "empty")
  (urdf-number :error (cl-urdf:parse-urdf 42) :match "42")
  (urdf-not-xml :error (cl-urdf:parse-urdf "hello robot") :match "XML")
  (urdf-no-links :error (cl-urdf:parse-urdf "<robot name=\"r\"/>") :match "link")
  (urdf-wrong-root :error (cl-urdf:parse-urdf "<model name=\"r\"/>") :match "model")
  (urdf-joint-cycle :error (cl-urdf:parse-urdf *cycle-urdf*) :match "\"ab\"")
  (urdf-lower-above-upper :error (cl-urdf:parse-urdf (tiny-urdf 1 -1)) :match "j1")
  (urdf-limit-not-number :error (cl-urdf:parse-urdf (tiny-urdf "low" 1)) :match "low")
  (urdf-limit-nan :error (cl-urdf:parse-urdf (tiny-urdf "nan" 1)) :match "nan")
  (urdf-simple-base-string :accepts
   (cl-urdf:parse-urdf (coerce (tiny-urdf) 'simple-base-string)))
  (urdf-base-string-add-object :accepts
   (in-small-world (btr:add-object w :urdf 'tiny (pose0) :urdf (coerce (tiny-urdf) 'simple-base-string))))
  (urdf-unknown-parent :error
   (cl-urdf:parse-urdf "<robot name=\"r\"><link name=\"a\"/><joint name=\"j\" type=\"fixed\"><parent link=\"nowhere\"/><child link=\"a\"/></joint></robot>")
   :match "nowhere")
  (urdf-duplicate-link :error
   (cl-urdf:parse-urdf "<robot name=\"r\"><link name=\"a\"/><link name=\"a\"/></robot>")
   :match "\"a\"")
  (urdf-bad-joint-type :error
   (cl-urdf:parse-urdf "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"twisty\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>")
   :match "twisty")
  (urdf-bad-origin :error
   (cl-urdf:parse-urdf "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"fixed\"><origin xyz=\"a b c\"/><parent link=\"a\"/><child link=\"b\"/></joint></robot>")
   :match "a b c")
  (urdf-zero-axis :error
   (cl-urdf:parse-urdf "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"continuous\"><axis xyz=\"0 0 0\"/><parent link=\"a\"/><child link=\"b\"/></joint></robot>")
   :match "0 0 0")
  (urdf-huge-box :error
   (in-small-world
     (btr:add-object w :urdf 'r (pose0)
                     :urdf "<robot name=\"r\"><link name=\"a\"><collision><geometry><box size=\"1e200 1 1\"/></geometry></collision></link></robot>"))
   :match "1e200"))

;;; ---- the simulated robot and its motions ------------------------------------------------

(defcases :urdf-proj
  (move-torso-nan :error (simulated (urdf-proj:move-torso (nan))) :match "NaN")
  (move-torso-string :error (simulated (urdf-proj:move-torso "up")) :match "\"up\"")
  (move-torso-huge :error (simulated (urdf-proj:move-torso 1d300)) :match "1.0d300")
  (drive-string :error (simulated (urdf-proj:drive "not a pose")) :match "not a pose")
  (drive-number :error (simulated (urdf-proj:drive 42)) :match "42")
  (drive-unknown-frame :error (simulated (urdf-proj:drive (ps "bad_input_frame" 0 0 0)))
   :match "bad_input_frame")
  (drive-huge :error (simulated (urdf-proj:drive (ps "map" 1d300 0 0))) :match "1.0d300")
  (look-at-number :error (simulated (urdf-proj:look-at 42)) :match "42")
  (look-at-unknown-frame :error (simulated (urdf-proj:look-at (ps "bad_input_frame" 1 0 1)))
   :match "bad_input_frame")
  (move-joints-nan :error (simulated (urdf-proj:move-joints (list (nan) 0 0 0 0 0 0) nil)) :match "NaN")
  (move-joints-short :error (simulated (urdf-proj:move-joints '(0 0) nil)) :match "(0 0)")
  (gripper-unknown-action :error (simulated (urdf-proj:gripper-action :bad-input-squeeze :left))
   :match ":BAD-INPUT-SQUEEZE")
  (gripper-unknown-arm :error (simulated (urdf-proj:gripper-action :open :middle)) :match ":MIDDLE")
  (gripper-position-nan :error (simulated (urdf-proj:gripper-action (nan) :left)) :match "NaN")
  (perform-torso-nan :error
   (simulated (exe:perform (desig:a motion (type moving-torso) (joint-angle (nan))))) :match "NaN")
  (perform-torso-string :error
   (simulated (exe:perform (desig:a motion (type moving-torso) (joint-angle "up")))) :match "\"up\"")
  (perform-going-number :error
   (simulated (exe:perform (desig:a motion (type going) (pose 42)))) :match "42")
  (perform-unknown-motion :error
   (simulated (exe:perform (desig:a motion (type bad-input-flying)))) :match "BAD-INPUT-FLYING")
  (perform-looking-string :error
   (simulated (exe:perform (desig:a motion (type looking) (target "up")))) :match "\"up\"")
  (perform-number :error (simulated (exe:perform 42)) :match "42")
  (solve-ik-number :error
   (simulated (urdf-proj:solve-ik (urdf-proj:arm-ik-chain :left) 42)) :match "42"))

;;; ---- costmaps ---------------------------------------------------------------------------

(defcases :costmap
  (costmap-negative-width :error (costmap:make-location-costmap :width -1 :height 1 :resolution 0.1
                                                                :origin-x 0 :origin-y 0)
   :match "-1")
  (costmap-zero-resolution :error (costmap:make-location-costmap :width 1 :height 1 :resolution 0
                                                                 :origin-x 0 :origin-y 0)
   :match "0")
  (costmap-nan-resolution :error (costmap:make-location-costmap :width 1 :height 1 :resolution (nan)
                                                                :origin-x 0 :origin-y 0)
   :match "NaN")
  (costmap-huge :error (costmap:make-location-costmap :width 1d200 :height 1 :resolution 0.1
                                                      :origin-x 0 :origin-y 0)
   :match "1.0d200")
  (costmap-origin-string :error (costmap:make-location-costmap :width 1 :height 1 :resolution 0.1
                                                               :origin-x "0" :origin-y 0)
   :match "\"0\"")
  (gauss-singular :error (costmap:make-gauss-cost-function '(0 0) '((0 0) (0 0))) :match "((0 0) (0 0))")
  (gauss-mean-string :error (costmap:make-gauss-cost-function "origin" '((1 0) (0 1))) :match "origin")
  (range-negative :error (costmap:make-range-cost-function '(0 0) -1) :match "-1")
  (range-nan :error (costmap:make-range-cost-function '(0 0) (nan)) :match "NaN")
  (register-on-number :error (costmap:register-cost-function 42 (lambda (x y) (+ x y)) 'f) :match "42")
  (register-non-function :error
   (costmap:register-cost-function (costmap:make-location-costmap :width 1 :height 1 :resolution 0.1
                                                                  :origin-x 0 :origin-y 0)
                                   42 'f)
   :match "42")
  (map-value-string :error
   (costmap:get-map-value (costmap:make-location-costmap :width 1 :height 1 :resolution 0.1
                                                         :origin-x 0 :origin-y 0)
                          "x" 0)
   :match "\"x\"")
  (cost-function-returns-nan :error
   (let ((c (costmap:make-location-costmap :width 1 :height 1 :resolution 0.1 :origin-x 0 :origin-y 0)))
     (costmap:register-cost-function c (lambda (x y) (declare (ignore x y)) (nan)) 'nan-fn)
     (costmap:get-cost-map c))
   :match "NaN")
  (cost-function-returns-string :error
   (let ((c (costmap:make-location-costmap :width 1 :height 1 :resolution 0.1 :origin-x 0 :origin-y 0)))
     (costmap:register-cost-function c (lambda (x y) (declare (ignore x y)) "high") 'str-fn)
     (costmap:get-cost-map c))
   :match "\"high\"")
  (samples-all-zero :error
   (let ((c (costmap:make-location-costmap :width 1 :height 1 :resolution 0.1 :origin-x 0 :origin-y 0)))
     (costmap:register-cost-function c (lambda (x y) (declare (ignore x y)) 0) 'zero)
     (cut:lazy-car (costmap:costmap-samples c)))
   :class costmap:invalid-probability-distribution)
  (seed-string :error (costmap:seed-costmaps "seven") :match "\"seven\"")
  (matrix-not-array :error (costmap:make-matrix-cost-function 0 0 0.1 42) :match "42")
  (height-nan :error (costmap:make-constant-height-function (nan)) :match "NaN")
  (padding-negative :error (costmap:make-padding-mask -2) :match "-2")
  (occupancy-grid-negative :error (costmap:make-occupancy-grid -1 1 0 0 0.1) :match "-1")
  (location-reachable-for-number :error
   (in-robot-world (desig:reference (desig:a location (reachable-for 42)))) :match "42")
  (location-visible-for-unknown :error
   (in-robot-world (desig:reference (desig:a location (visible-for bad-input-robot))))
   :match "BAD-INPUT-ROBOT"))
