;;;; Packages of the transforms layer.
;;;;
;;;; CL-TRANSFORMS   vectors, quaternions, poses and transforms (pure maths).
;;;; CL-TRANSFORMS-STAMPED   frame-stamped poses, points and transforms, and the TF transformer.
;;;; CL-TF   re-exports both, so `cl-tf:make-pose-stamped' and `cl-tf:make-3d-vector' work.
;;;; CRAM-TF   the robot-level frame conventions and pose helpers.

(defpackage :cl-transforms
  (:use :cl)
  (:export
   ;; conditions
   #:transform-input-error #:transform-input-error-value #:transform-input-error-expected
   ;; 3d vectors
   #:3d-vector #:3d-vector-p #:point #:make-3d-vector #:make-identity-vector #:copy-3d-vector
   #:x #:y #:z #:w
   #:v+ #:v- #:v* #:v/ #:v-inv #:v*-pairwise #:v/-pairwise #:v= #:dot-product #:cross-product
   #:v-norm #:v-dist #:normalize-vector #:interpolate-vector
   ;; quaternions
   #:quaternion #:quaternion-p #:make-quaternion #:make-identity-rotation #:copy-quaternion
   #:q* #:q-inv #:q= #:q-dot #:q+ #:q- #:q-norm #:normalize #:is-normalized #:rotate
   #:axis-angle->quaternion #:quaternion->axis-angle
   #:euler->quaternion #:quaternion->euler #:get-yaw #:yaw
   #:angle-between-quaternions #:normalize-angle #:slerp
   #:quaternion->matrix #:matrix->quaternion
   ;; poses and transforms
   #:pose #:pose-p #:make-pose #:make-identity-pose #:copy-pose #:make-2d-pose
   #:origin #:orientation
   #:transform #:transform-p #:make-transform #:make-identity-transform #:copy-transform
   #:translation #:rotation
   #:pose->transform #:transform->pose #:reference-transform
   #:transform* #:transform-inv #:transform-diff #:transform-point #:transform-pose
   #:transform->matrix #:matrix->transform #:pose->matrix #:matrix->pose))

(in-package :cl-transforms)

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun %external-names (packages)
    "The names of every external symbol of PACKAGES, sorted, without duplicates."
    (let ((names '()))
      (dolist (p packages)
        (do-external-symbols (s p)
          (pushnew (symbol-name s) names :test #'string=)))
      (sort names #'string<))))

(defmacro define-reexporting-package (name (&rest from) &body options)
  "DEFPACKAGE NAME with OPTIONS that also exports every external name of the packages FROM."
  `(defpackage ,name
     ,@options
     (:export ,@(%external-names from))))

(define-reexporting-package :cl-transforms-stamped (:cl-transforms)
  (:use :cl :cl-transforms)
  (:export
   #:pose-stamped #:pose-stamped-p #:make-pose-stamped #:pose->pose-stamped
   #:pose-stamped->pose #:copy-pose-stamped #:ensure-pose-stamped
   #:transform-stamped #:transform-stamped-p #:make-transform-stamped
   #:transform->transform-stamped #:transform-stamped->transform #:copy-transform-stamped
   #:point-stamped #:point-stamped-p #:make-point-stamped #:point-stamped->point
   #:copy-point-stamped
   #:frame-id #:child-frame-id #:stamp #:normalize-frame-name
   ;; the transformer
   #:transformer #:set-transform #:defer-update #:with-transforms-batch #:lookup-transform
   #:can-transform #:wait-for-transform
   #:transform-pose-stamped #:transform-point-stamped #:clear #:frame-exists #:known-frames
   #:transform-stamped-error #:tf-lookup-error #:tf-connectivity-error #:tf-extrapolation-error
   #:transform-stamped-error-target-frame #:transform-stamped-error-source-frame))

(define-reexporting-package :cl-tf (:cl-transforms :cl-transforms-stamped)
  (:use :cl :cl-transforms :cl-transforms-stamped))

(defpackage :cram-tf
  (:use :cl :cl-transforms :cl-transforms-stamped)
  (:export
   #:*transformer* #:*fixed-frame* #:*robot-base-frame* #:*odom-frame* #:*robot-torso-frame*
   #:*robot-torso-joint* #:*robot-left-tool-frame* #:*robot-right-tool-frame*
   #:*tf-default-timeout*
   #:robot-current-pose #:frame-to-pose-in-fixed-frame
   #:rotate-pose #:angle-around-map-z #:translate-pose #:translate-transform-stamped
   #:pose-stamped->transform-stamped #:transform-stamped->pose-stamped #:strip-transform-stamped
   #:pose->transform-stamped #:transform-stamped-inv #:multiply-transform-stampeds
   #:apply-transform #:copy-transform-stamped
   #:ensure-pose-in-frame #:ensure-point-in-frame
   #:pose->list #:list->pose #:pose->flat-list #:flat-list->pose
   #:pose->flat-list-w-first #:flat-list-w-first->pose
   #:pose-stamped->list #:list->pose-stamped
   #:poses-equal-p #:tf-frame-converged))
