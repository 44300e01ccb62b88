;;;; Package CRAM-PR2-DESCRIPTION (nickname PR2-DESCR): the PR2 as Prolog facts keyed by
;;;; the robot name :PR2 (the keyword of the URDF robot name "pr2").

(in-package :cl-user)

(defpackage :cram-pr2-description
  (:nicknames :pr2-descr)
  (:use :cl :cram-prolog :cram-robot-interfaces)
  (:export #:*left-parking-joint-states* #:*right-parking-joint-states*
           #:*tcp-in-ee-pose* #:*standard-to-pr2-gripper-transform*))
