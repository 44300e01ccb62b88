;;;; The seed-era (2017) API of src/compat/: each alias does what today's name does.

(defpackage :cram-compat-tests
  (:use :cl :fiveam))

(in-package :cram-compat-tests)

(def-suite compat :in cram-plans-tests:all
  :description "CRAM compatibility for the seed-era API (src/compat/).")
(in-suite compat)

(defun fresh-kitchen ()
  (let ((*standard-output* (make-broadcast-stream)))
    (btw-tut:init-projection)))

(test compat-packages-and-names
  "The era's packages and names exist and point at today's implementation."
  (is (eq (find-package :pr2-pp-plans) (find-package :cram-pr2-pick-place-plans)))
  (is (eq 'pp-plans:park-arms (find-symbol "PARK-ARMS" :pr2-pp-plans)))
  (is (eq :external (nth-value 1 (find-symbol "PR2" :cram-pr2-description))))
  (dolist (f '(cram-occupancy-grid-costmap:init-occupancy-grid-costmap btr-belief:ros-time-init
               cram-location-costmap:location-costmap-vis-init cram-tf:init-tf))
    (is (fboundp f))
    (is-true (nth-value 1 (gethash f roslisp-utilities:*ros-init-functions*)) "~s is not a ROS init function" f)))

(test compat-occupancy-grid
  "init-occupancy-grid-costmap reads the kitchen map: walls occupied, the room free."
  (let ((g (cram-occupancy-grid-costmap:init-occupancy-grid-costmap)))
    (is (eq g (cram-occupancy-grid-costmap:occupancy-grid)))
    (is (= 0.05d0 (cram-occupancy-grid-costmap:occupancy-grid-resolution g)))
    (is (cram-occupancy-grid-costmap:occupied-p 100 100) "off the map counts as occupied")
    (is (not (cram-occupancy-grid-costmap:occupied-p 0 0)) "the robot's start is free")))

(test compat-init-tf-and-clock
  (let ((old cram-tf:*transformer*))
    (cram-tf:init-tf)
    (is (not (eq old cram-tf:*transformer*))))
  (btr-belief:ros-time-init)
  (is (< (btr-belief:belief-time) 1)))

(test compat-parking-facts-and-names
  "robot-arms-parking-joint-states gives both arms' park states; PR2 and :kitchen resolve."
  (fresh-kitchen)
  (let* ((b (cut:lazy-car (prolog:prolog '(and (cram-robot-interfaces:robot ?r)
                                               (cram-robot-interfaces:robot-arms-parking-joint-states ?r ?js)))))
         (js (cut:var-value '?js b)))
    (is (= 14 (length js)))
    (is (equal js (append (rob-int:get-robot-joint-states :pr2 :arm :left :park)
                          (rob-int:get-robot-joint-states :pr2 :arm :right :park)))))
  (is (eq (btr:object btr:*current-bullet-world* :pr2)
          (btr:object btr:*current-bullet-world* 'cram-pr2-description:pr2)))
  (is (eq (btr:get-environment-object) (btr:object btr:*current-bullet-world* :kitchen)))
  (is (null (btr:object btr:*current-bullet-world* :no-such-thing))))

(test compat-semantic-map-object
  "A :semantic-map object with :urdf becomes the environment."
  (fresh-kitchen)
  (btr:remove-object btr:*current-bullet-world* btr:*environment-name*)
  (prolog:prolog `(and (btr:bullet-world ?w)
                       (assert (btr:object ?w :semantic-map :kitchen ((0 0 0) (0 0 0 1))
                                           :urdf ,(btw-tut:get-kitchen-urdf)))))
  (is (eq :kitchen btr:*environment-name*))
  (is (member "kitchen_island_surface" (btr:link-names (btr:object btr:*current-bullet-world* :kitchen))
              :test #'string=)))

(test compat-location-vocabulary
  "(:on \"CounterTop\") (:name ...) samples the island top; (:to :see) a base pose; unknown keys err."
  (fresh-kitchen)
  (let* ((on (desig:make-designator :location '((:on "CounterTop")
                                                 (:name "iai_kitchen_kitchen_island_counter_top"))))
         (p (desig:reference on))
         (o (cl-transforms:origin p)))
    (is (< -1.47 (cl-transforms:x o) -0.67))
    (is (< 0.5 (cl-transforms:y o) 2.9))
    (is (< 0.8 (cl-transforms:z o) 0.9))
    (let* ((see (desig:make-designator :location `((:to :see) (:location ,on))))
           (base (desig:reference see)))
      (is (< (abs (cl-transforms:z (cl-transforms:origin base))) 1d-6))))
  (signals error (desig:reference (desig:make-designator :location '((:to :fly)))))
  (handler-case (progn (desig:reference (desig:make-designator :location '((:near-by "x"))))
                       (fail "an unknown key resolved"))
    (error (e)
      (is (search ":NEAR-BY" (princ-to-string e)))
      (is (search ":visible-for" (string-downcase (princ-to-string e))) "the message lists the keys that exist"))))

(test compat-old-surface-names
  (fresh-kitchen)
  (let ((env (btr:get-environment-object)))
    (is (string= "kitchen_island_surface"
                 (cram-plans-compat:old-surface-link "iai_kitchen_kitchen_island_counter_top" env)))
    (is (string= "sink_area_surface"
                 (cram-plans-compat:old-surface-link "iai_kitchen_sink_area_counter_top" env)))
    (signals error (cram-plans-compat:old-surface-link "iai_kitchen_moon_counter_top" env))))

(test compat-moving-joints-and-looking-at
  "Motion MOVING-JOINTS moves the arms to the values given; action LOOKING-AT grounds as LOOKING."
  (fresh-kitchen)
  (let ((pr2 (btr:get-robot-object)))
    (btr:set-robot-state-from-joints '(("l_shoulder_pan_joint" 0.0d0)) pr2)
    (urdf-proj:with-simulated-robot
      (let ((?l pr2-pp-plans:*pr2-left-arm-out-of-sight-joint-positions*))
        (exe:perform (desig:a motion (type moving-joints) (left-configuration ?l)))))
    (is (< (abs (- (btr:joint-state pr2 "l_shoulder_pan_joint")
                   (second (first (rob-int:get-robot-joint-states :pr2 :arm :left :park)))))
           1d-6)))
  (is (member :looking-at (pp-plans:action-types))))

(defun compat-init-x () :x)
(defun compat-init-y () :y)

(test compat-ros-init-functions-hash-table
  "*ros-init-functions* is a hash table keyed by function name, as in CRAM; startup order is kept."
  (is (hash-table-p roslisp-utilities:*ros-init-functions*))
  (is (member 'cram-tf:init-tf (alexandria:hash-table-keys roslisp-utilities:*ros-init-functions*)))
  (let ((roslisp-utilities:*ros-init-functions* (roslisp-utilities:make-function-registry)))
    (roslisp-utilities:register-ros-init-function compat-init-y)
    (roslisp-utilities:register-ros-init-function compat-init-x)
    (roslisp-utilities:register-ros-init-function compat-init-y)
    (is (equal '(compat-init-y compat-init-x) (roslisp-utilities:ros-init-functions)))
    (is (= 2 (hash-table-count roslisp-utilities:*ros-init-functions*)))
    (is (eq :x (funcall (gethash 'compat-init-x roslisp-utilities:*ros-init-functions*))))
    (is-true (roslisp-utilities:unregister-ros-init-function 'compat-init-y))
    (is (equal '(compat-init-x) (roslisp-utilities:ros-init-functions)))
    ;; a name put in by hand, as CRAM code may do, runs after the registered ones
    (setf (gethash 'compat-init-y roslisp-utilities:*ros-init-functions*) #'compat-init-y)
    (is (equal '(compat-init-x compat-init-y) (roslisp-utilities:ros-init-functions))))
  (is-false (member 'compat-init-x (roslisp-utilities:ros-init-functions))))

(defun compat-test-far-away-generator (designator)
  (let ((p (desig:desig-prop-value designator :compat-test-far-away)))
    (if p (list (cl-transforms:make-pose (cl-transforms:make-3d-vector p 0 0)
                                         (cl-transforms:make-identity-rotation)))
        '())))

(test compat-user-location-keys-are-not-unknown
  "A key only a user's generator (registered after the compat layer) handles resolves; a key
nobody handles is named in the error."
  (unwind-protect
       (progn
         (desig:register-location-generator 50 compat-test-far-away-generator)
         (let ((p (desig:reference (desig:make-designator :location '((:compat-test-far-away 7))))))
           (is (= 7 (cl-transforms:x (cl-transforms:origin p))))))
    (desig:delete-location-generator-function 'compat-test-far-away-generator))
  (let ((e (handler-case (desig:reference (desig:make-designator :location '((:compat-test-far-away 7))))
             (error (e) e))))
    (is (typep e 'desig:location-resolution-error))
    (is (search ":COMPAT-TEST-FAR-AWAY" (princ-to-string e)))))
