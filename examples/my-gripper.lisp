;;;; A process module for your own gripper, written as a CRAM user writes one: an actionlib
;;;; client of the gripper's action server (tools/ros/gripper_action_server.py stands for it),
;;;; a motion designator that grounds to a command, the process module that runs the command,
;;;; and the rule that matches the two. The gripper's action is actionlib/TestAction: the goal
;;;; is the opening in millimetres, the feedback the current opening, the result the opening
;;;; reached.
;;;;
;;;;   (load "examples/my-gripper.lisp")          ; with cram-plans/cram-ros-pms loaded
;;;;   (my-gripper:init-my-gripper)               ; with a ROS node running
;;;;   (cpl:top-level
;;;;     (cpm:with-process-modules-running (my-gripper:my-gripper-pm)
;;;;       (exe:perform (desig:a motion (type setting-my-gripper) (opening 0.04)))))   ; => 0.04

(asdf:load-system "actionlib-msg")      ; the messages of actionlib/TestAction (Debian's cl-actionlib)

(defpackage :my-gripper
  (:use :cl)
  (:export #:init-my-gripper #:my-gripper-pm #:*gripper-action* #:*gripper-feedback*))

(in-package :my-gripper)

(defparameter *gripper-action* "/my_gripper/command"
  "The ROS name of the gripper's action server.")

(defvar *gripper-feedback* '()
  "The openings (metres) the gripper reported while it moved, newest first.")

(defun init-my-gripper ()
  "Register the gripper's action client (made on the first command)."
  (actionlib-client:make-simple-action-client
   'gripper-action *gripper-action* "actionlib/TestAction" 5))

(defun set-gripper-opening (opening)
  "Open or close the gripper to OPENING metres; returns the opening it reached. A goal the
gripper does not reach is a GRIPPER-GOAL-NOT-REACHED failure, which plans can recover from."
  (let ((goal (actionlib:make-action-goal
               (actionlib-client:get-simple-action-client 'gripper-action)
               goal (round (* 1000 opening)))))
    (setf *gripper-feedback* '())
    (multiple-value-bind (result state)
        (actionlib-client:call-simple-action-client
         'gripper-action :action-goal goal
                         :feedback-cb (lambda (feedback)
                                        (push (/ (actionlib-msg:feedback feedback) 1000.0d0)
                                              *gripper-feedback*)))
      (unless (eq state :succeeded)
        (cpl:fail 'common-fail:gripper-goal-not-reached
                  :description (format nil "The gripper did not reach ~,3f m: ~(~a~)." opening state)))
      (/ (actionlib-msg:result result) 1000.0d0))))

;; (desig:a motion (type setting-my-gripper) (opening 0.04)) grounds to (set-opening 0.04) ...
(prolog:def-fact-group my-gripper-motions (desig:motion-grounding)
  (prolog:<- (desig:motion-grounding ?designator (set-opening ?opening))
    (desig:desig-prop ?designator (:type :setting-my-gripper))
    (desig:desig-prop ?designator (:opening ?opening))))

;; ... which this process module executes ...
(cpm:def-process-module my-gripper-pm (motion-designator)
  "Executes SETTING-MY-GRIPPER motions with the gripper's action server."
  (destructuring-bind (command opening) (desig:reference motion-designator)
    (ecase command
      (set-opening (set-gripper-opening opening)))))

;; ... and this rule chooses it for such motions.
(prolog:def-fact-group my-gripper-pm-matching (cpm:matching-process-module)
  (prolog:<- (cpm:matching-process-module ?designator my-gripper-pm)
    (desig:desig-prop ?designator (:type :setting-my-gripper))))
