;;;; The era's belief-state names: the robot called CRAM-PR2-DESCRIPTION:PR2, the kitchen called
;;;; :KITCHEN, kitchens spawned as :SEMANTIC-MAP objects, the arms' parking facts, and the init
;;;; functions the tutorial called by hand (occupancy map, clock, costmap markers, TF).

(in-package :cram-plans-compat)

;;; ---- object names ------------------------------------------------------------------------------

(defvar *object-name-aliases*
  (list (cons (find-symbol "PR2" :cram-pr2-description) :pr2))
  "Old object names and the names they stand for: CRAM-PR2-DESCRIPTION:PR2 is :PR2 (the name
ROB-INT:ROBOT gives today). :KITCHEN stands for the environment when nothing is called :KITCHEN.")

(defun resolve-old-object-name (world name)
  "The current name of the object the era's NAME meant, or NIL."
  (declare (ignore world))
  (or (cdr (assoc name *object-name-aliases*))
      (and (eq name :kitchen) btr:*environment-name*)))

(pushnew 'resolve-old-object-name btr::*object-name-resolvers*)

;;; ---- :semantic-map objects: the kitchen URDF as the environment ------------------------------

(defmethod btr:add-object :around ((world btr:bt-reasoning-world) (type (eql :semantic-map)) name pose
                                   &rest keys &key urdf &allow-other-keys)
  "A :SEMANTIC-MAP object is the environment: its URDF (:URDF, default the kitchen of
BTW-TUT:GET-KITCHEN-URDF) as a static articulated object, named the environment."
  (let ((urdf (or urdf (funcall (find-symbol "GET-KITCHEN-URDF" :btw-tut))))
        (rest (loop for (k v) on keys by #'cddr unless (eq k :urdf) append (list k v))))
    (prog1 (apply #'btr:add-object world :urdf name pose :urdf urdf
                  :collision-group :static-filter
                  :collision-mask '(:default-filter :character-filter) rest)
      (setf btr:*environment-name* name))))

;;; ---- robot facts ---------------------------------------------------------------------------

(def-fact-group compat-robot-facts (rob-int:robot-arms-parking-joint-states)
  (<- (rob-int:robot-arms-parking-joint-states ?robot ?joint-states ?arm)
    (rob-int:arm ?robot ?arm)
    (rob-int:robot-joint-states ?robot :arm ?arm :park ?joint-states))
  (<- (rob-int:robot-arms-parking-joint-states ?robot ?joint-states)
    (rob-int:robot-joint-states ?robot :arm :left :park ?left)
    (rob-int:robot-joint-states ?robot :arm :right :park ?right)
    (lisp-fun append ?left ?right ?joint-states)))

;;; ---- the init functions ------------------------------------------------------------------------

(defun cram-tf::init-tf ()
  "A fresh TF buffer in CRAM-TF:*TRANSFORMER* (what CRAM's INIT-TF made: a new listener)."
  (setf cram-tf:*transformer* (make-instance 'cl-tf:transformer)))

(defun cram-location-costmap::location-costmap-vis-init ()
  "Start the costmap visualization afresh: forget the costmaps of earlier designators, so the
next heat map (COSTMAP-HEAT-MAP-PNG) and markers show only new ones. Returns T."
  (clrhash costmap::*scratch-worlds*)
  t)

(defvar btr-belief::*time-origin* nil "Wall-clock seconds at ROS-TIME-INIT.")

(defun btr-belief:belief-time ()
  "Seconds since ROS-TIME-INIT (0 before it was called)."
  (if btr-belief::*time-origin*
      (- (/ (get-internal-real-time) internal-time-units-per-second) btr-belief::*time-origin*)
      0))

(defun btr-belief:ros-time-init ()
  "Reset the belief state's clock (BELIEF-TIME) to 0; returns the time origin."
  (setf btr-belief::*time-origin* (/ (get-internal-real-time) internal-time-units-per-second)))

(roslisp-utilities:register-ros-init-function cram-occupancy-grid-costmap:init-occupancy-grid-costmap)
(roslisp-utilities:register-ros-init-function btr-belief:ros-time-init)
(roslisp-utilities:register-ros-init-function cram-location-costmap::location-costmap-vis-init)
(roslisp-utilities:register-ros-init-function cram-tf::init-tf)
