;;;; CL-BULLET's bounding boxes (centre and dimensions) as CRAM code reads them, for objects of a
;;;; Bullet world too; BTR:CALCULATE-BB-DIMS and BTR:MERGE-BOUNDING-BOXES.

(defpackage :cl-bullet
  (:use :cl)
  (:export #:bounding-box #:make-bounding-box #:bounding-box-p
           #:bounding-box-center #:bounding-box-dimensions))

(in-package :cl-bullet)

(defstruct (bounding-box (:constructor %make-bounding-box (center dimensions)) (:copier nil)
                         (:conc-name %bb-))
  "An axis-aligned box given by its centre and its dimensions (CL-TRANSFORMS:3D-VECTORs)."
  (center nil :type cl-transforms:3d-vector :read-only t)
  (dimensions nil :type cl-transforms:3d-vector :read-only t))

(setf (documentation 'bounding-box-p 'function) "True when the object is a BOUNDING-BOX.")

(defun make-bounding-box (&key center dimensions)
  "A BOUNDING-BOX with CENTER and DIMENSIONS (3D-VECTORs; no dimension negative)."
  (unless (typep center 'cl-transforms:3d-vector)
    (error "MAKE-BOUNDING-BOX: the centre ~s is not a CL-TRANSFORMS:3D-VECTOR." center))
  (unless (and (typep dimensions 'cl-transforms:3d-vector)
               (>= (cl-transforms:x dimensions) 0) (>= (cl-transforms:y dimensions) 0)
               (>= (cl-transforms:z dimensions) 0))
    (error "MAKE-BOUNDING-BOX: the dimensions ~s are not a 3D-VECTOR without negative sizes."
           dimensions))
  (%make-bounding-box center dimensions))

(defgeneric bounding-box (object)
  (:documentation "The axis-aligned BOUNDING-BOX of OBJECT (a bounding box is its own).")
  (:method ((box bounding-box)) box)
  (:method ((object t))
    (error "CL-BULLET:BOUNDING-BOX: ~s is neither a bounding box nor an object of a Bullet world."
           object)))

(defun bounding-box-center (box)
  "The centre of BOX: a BOUNDING-BOX, or an object of a Bullet world (its axis-aligned box)."
  (%bb-center (bounding-box box)))

(defun bounding-box-dimensions (box)
  "The dimensions (x y z sizes) of BOX: a BOUNDING-BOX, or an object of a Bullet world."
  (%bb-dimensions (bounding-box box)))

(in-package :cram-bullet-reasoning)

(defmethod cl-bullet:bounding-box ((object object))
  (multiple-value-bind (lo hi) (aabb object)
    (cl-bullet:make-bounding-box :center (cl-transforms:v* (cl-transforms:v+ lo hi) 0.5d0)
                                 :dimensions (cl-transforms:v- hi lo))))

(defun calculate-bb-dims (object)
  "The dimensions of the axis-aligned bounding box of OBJECT, a 3D-VECTOR."
  (cl-bullet:bounding-box-dimensions object))

(defun merge-bounding-boxes (&rest boxes)
  "The smallest BOUNDING-BOX holding every one of BOXES (bounding boxes or objects)."
  (when (null boxes) (btr-fail "MERGE-BOUNDING-BOXES: no bounding box given"))
  (let ((lo (list most-positive-double-float most-positive-double-float most-positive-double-float))
        (hi (list most-negative-double-float most-negative-double-float most-negative-double-float)))
    (dolist (b boxes)
      (let* ((box (cl-bullet:bounding-box b))
             (c (cl-bullet:bounding-box-center box))
             (d (cl-bullet:bounding-box-dimensions box)))
        (loop for axis in (list #'cl-transforms:x #'cl-transforms:y #'cl-transforms:z)
              for i from 0
              do (setf (nth i lo) (min (nth i lo) (- (funcall axis c) (/ (funcall axis d) 2)))
                       (nth i hi) (max (nth i hi) (+ (funcall axis c) (/ (funcall axis d) 2)))))))
    (cl-bullet:make-bounding-box
     :center (apply #'cl-transforms:make-3d-vector (mapcar (lambda (a b) (/ (+ a b) 2)) lo hi))
     :dimensions (apply #'cl-transforms:make-3d-vector (mapcar #'- hi lo)))))
