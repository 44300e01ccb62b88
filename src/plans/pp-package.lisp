;;;; Package CRAM-MOBILE-PICK-PLACE-PLANS (PP-PLANS): action groundings and plans of a mobile
;;;; manipulator — going, looking, detecting, torso, arms, grippers, picking up and placing.

(defpackage :cram-mobile-pick-place-plans
  (:nicknames :pp-plans)
  (:use :cl :cram-prolog)
  (:export
   ;; plans
   #:navigate #:look-at #:perceive #:move-torso #:position-arms #:park-arms
   #:set-gripper #:grip #:release #:move-arms-in-sequence #:pick-up #:place
   ;; groundings and helpers
   #:ground-action #:action-types #:pose-in-map #:current-robot-name
   #:object-designator-name #:object-designator-type #:object-pose-in-map
   #:support-height-below
   #:*look-z-offset* #:pick-place-error))

(in-package :cram-mobile-pick-place-plans)

(define-condition pick-place-error (simple-error) ()
  (:documentation "Bad input to a pick-and-place action: the message names the value and what
was expected."))

(defun pp-error (control &rest arguments)
  (error 'pick-place-error :format-control control :format-arguments arguments))

(defparameter *look-z-offset* 0.0
  "Metres added to the height of an object's pose when looking at it.")
