;;;; Packages of the executive layer.
;;;;
;;;; CRAM-OCCASIONS-EVENTS (COE)        the ON-EVENT hook, HOLDS, CLEAR-BELIEF.
;;;; CRAM-PLAN-OCCASIONS-EVENTS (CPOE)  the event classes plans fire and the occasion predicates.
;;;; CRAM-PROCESS-MODULES (CPM)         process modules and their dispatch.
;;;; CRAM-PROJECTION (PROJ)             projection environments.
;;;; CRAM-EXECUTIVE (EXE)               PERFORM.

(defpackage :cram-occasions-events
  (:nicknames :coe)
  (:use :cl)
  (:export
   #:event #:event-timestamp #:on-event #:holds #:clear-belief #:occasion-functor-error))

(defpackage :cram-plan-occasions-events
  (:nicknames :cpoe)
  (:use :cl :cram-occasions-events)
  (:export
   ;; events
   #:robot-state-changed #:object-perceived-event #:object-attached-robot
   #:object-detached-robot #:object-attached-object #:object-detached-object
   #:object-location-changed #:container-opening-event #:container-closing-event
   #:environment-manipulation-event
   ;; event slot readers
   #:event-object-name #:event-object-designator #:event-other-object-name
   #:event-attachment-type #:event-arm #:event-grasp #:event-link #:event-not-loose
   #:event-perception-source #:event-location-designator #:event-joint-name
   #:event-environment-name #:event-environment-designator #:event-distance
   ;; occasion predicates
   #:object-in-hand #:object-at-location #:robot-at-location #:looking-at #:torso-at
   #:arms-positioned-at #:tool-frames-at #:gripper-joint-at #:gripper-opened
   #:gripper-closed #:container-state #:object-attached-to
   #:location-accessible #:location-reset))

(defpackage :cram-process-modules
  (:nicknames :cpm)
  (:use :cl)
  (:export
   #:process-module #:process-module-name #:def-process-module #:find-process-module
   #:process-module-names #:with-process-modules-running #:running-process-modules
   #:process-module-running-p #:pm-execute #:pm-execute-matching
   #:matching-process-modules #:matching-process-module #:available-process-module
   #:process-module-error #:process-module-error-name
   #:no-matching-process-module #:no-matching-process-module-designator
   #:resolve-process-module-name
   ;; asynchronous process modules
   #:def-asynchronous-process-module #:asynchronous-process-module
   #:asynchronous-process-module-name #:on-input #:on-cancel #:on-run #:synchronization-fluent
   #:finish-process-module #:fail-process-module #:monitor-process-module
   #:*process-module-debugger-hook* #:continue-pm))

(defpackage :cram-projection
  (:nicknames :proj)
  (:use :cl)
  (:export
   #:define-projection-environment #:with-projection-environment #:*projection-environment*
   #:projection-environment-names #:projection-environment-process-modules
   ;; clocks and special projection variables
   #:clock-time #:clock-wait #:linear-clock #:partially-ordered-clock
   #:partially-ordered-clock-enabled #:with-partially-ordered-clock-disabled
   #:define-special-projection-variable))

(defpackage :cram-executive
  (:nicknames :exe)
  (:use :cl)
  (:export #:perform #:action-plan-arguments))
