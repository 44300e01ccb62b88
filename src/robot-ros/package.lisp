;;;; Package CRAM-ROS-PMS (nickname PR2-PMS): plans on a robot over ROS 1.
;;;;
;;;; This file is the light part, loaded with `cram-plans': the package, the connection error
;;;; and WITH-REAL-ROBOT, which loads the system "cram-plans/cram-ros-pms" (roslisp's message
;;;; systems, the process modules) the first time it runs. See docs/robot-over-ros.md.

(defpackage :cram-ros-pms
  (:nicknames :pr2-pms)
  (:use :cl)
  (:export
   ;; running plans on the robot
   #:with-real-robot #:call-with-real-robot #:load-robot-system #:real-robot-environment
   #:robot-connection-error #:robot-connection-error-name #:robot-connection-error-reason
   ;; settings
   #:*robot-namespace* #:*motion-timeout* #:*stall-timeout* #:*navigation-timeout*
   #:*silence-timeout* #:*connect-timeout* #:*master-check-interval* #:*joint-tolerance*
   #:*camera-range* #:*joint-speed*
   ;; the robot's state and the belief state
   #:robot-joint-positions #:robot-base-pose #:sync-belief-state
   ;; the action client
   #:action-client #:make-action-client #:send-goal #:cancel-goal #:wait-for-result
   #:action-client-name #:close-action-client
   ;; process modules
   #:ros-navigation #:ros-torso #:ros-neck #:ros-perception #:ros-grippers #:ros-arms))

(in-package :cram-ros-pms)

(define-condition robot-connection-error (error)
  ((name :initarg :name :reader robot-connection-error-name
         :documentation "The topic, action, parameter or master URI that failed, as ROS names it.")
   (reason :initarg :reason :reader robot-connection-error-reason
           :documentation "What happened, a sentence."))
  (:report (lambda (condition stream)
             (format stream "Robot connection lost on ~a: ~a"
                     (robot-connection-error-name condition)
                     (robot-connection-error-reason condition))))
  (:documentation "The robot or the ROS master stopped answering: a topic stayed silent, an
action server did not answer, or the master is unreachable. Not a plan failure: plans do not
recover from it, it leaves WITH-REAL-ROBOT."))

(setf (documentation 'robot-connection-error-name 'function)
      "The topic, action or master URI a ROBOT-CONNECTION-ERROR is about."
      (documentation 'robot-connection-error-reason 'function)
      "The text of a ROBOT-CONNECTION-ERROR saying what went wrong.")

(defvar *robot-namespace* ""
  "The ROS namespace of the robot's interfaces (\"\" or \"/\": the root; e.g. \"/sim\"). Topic
and action names of docs/robot-over-ros.md are taken relative to it.")

(defun load-robot-system ()
  "Load the system \"cram-plans/cram-ros-pms\" (roslisp's message systems and the robot
process modules) unless it is loaded. WITH-REAL-ROBOT calls it; calling it first only moves
the load time (about 0.3 s warm) out of the first plan run. Returns T."
  (unless (fboundp (find-symbol "%CALL-WITH-REAL-ROBOT" :cram-ros-pms))
    (handler-bind ((warning #'muffle-warning))
      (asdf:load-system "cram-plans/cram-ros-pms")))
  t)

(defun call-with-real-robot (thunk)
  "Run THUNK (a function of no arguments) as WITH-REAL-ROBOT runs its body; returns its values."
  (load-robot-system)
  (funcall (find-symbol "%CALL-WITH-REAL-ROBOT" :cram-ros-pms) thunk))

(defmacro with-real-robot (&body body)
  "Run BODY as a top-level plan on the robot over ROS (the twin of
URDF-PROJ:WITH-SIMULATED-ROBOT): motion designators go to the robot process modules (move_base,
joint trajectory controllers, perception/objects), and the Bullet belief state follows the
robot (joints from /joint_states, base from TF, detected objects). A plan written for projection
runs unchanged, also when it calls WITH-SIMULATED-ROBOT itself (that environment is then this
one). Needs a running node (ROSLISP-UTILITIES:STARTUP-ROS) and the robot's interfaces; every wait
has a timeout and a lost master or a silent robot signals ROBOT-CONNECTION-ERROR. Loads the
system \"cram-plans/cram-ros-pms\" on first use. Returns the first value of BODY."
  `(values (call-with-real-robot (lambda () ,@body))))
