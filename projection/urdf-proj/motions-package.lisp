;;;; Package CRAM-COMMON-DESIGNATORS (nickname COMMON-DESIG): the MOTION-GROUNDING rules of
;;;; every robot-independent motion and the waiting process module.

(defpackage :cram-common-designators
  (:nicknames :common-desig)
  (:use :cl :cram-prolog)
  (:export
   ;; process module
   #:wait-pm
   ;; motion commands (the first element of a grounded motion designator)
   #:drive #:move-torso #:look-at #:detect #:move-gripper-joint #:move-tcp #:move-joints
   #:monitor-joint-state #:wait-for #:position-arms
   ;; helpers
   #:motion-command #:motion-arguments #:*known-motion-types*))
