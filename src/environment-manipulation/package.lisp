;;;; Package CRAM-URDF-ENVIRONMENT-MANIPULATION (ENV-MAN): opening and closing the drawers and
;;;; doors of an articulated environment (a URDF object of the belief state such as the
;;;; kitchen), and accessing and sealing the locations inside them.

(defpackage :cram-urdf-environment-manipulation
  (:nicknames :env-man)
  (:use :cl :cram-prolog)
  (:export
   ;; parameters
   #:*container-state-convergence-delta* #:*handle-pregrasp-offset* #:*handle-retract-offset*
   #:*revolute-trajectory-step* #:*handle-grasps*
   ;; errors
   #:environment-manipulation-error
   ;; containers of an environment
   #:container #:find-container #:container-environment #:container-link #:container-handle #:container-name
   #:container-joint #:container-joint-type #:container-links #:container-joint-state
   #:container-joint-limits #:container-opening-amount #:container-default-target
   #:container-designator-container
   ;; trajectories and base poses
   #:handle-grasp-transform #:container-trajectory #:container-base-poses #:container-base-pose-finder
   ;; belief state
   #:attach-object-to-touched-links #:detach-object-from-environment
   #:*environment-joint-state-hooks*
   ;; plans
   #:manipulate-container #:access-or-seal-location))

(in-package :cram-urdf-environment-manipulation)

(define-condition environment-manipulation-error (simple-error) ()
  (:documentation "Bad input to an environment manipulation action or function: an unknown
environment or container, a link that is no container, a bad distance, arm or grasp. The
message names the value as it was written and what was expected."))

(defun env-error (control &rest arguments)
  "Signal an ENVIRONMENT-MANIPULATION-ERROR with the formatted message."
  (error 'environment-manipulation-error :format-control control :format-arguments arguments))

(defun log-env (tag control &rest arguments)
  "Log at :INFO under (ENV-MAN TAG), as CRAM's plans log their steps."
  (apply #'cpl:log-message :info `(env-man ,tag) control arguments))

(defun d (x)
  "The real X as a double float; a single float by its printed decimal (0.3 → 0.3d0), as the
belief state reads the numbers a user types."
  (btr::to-double x))
