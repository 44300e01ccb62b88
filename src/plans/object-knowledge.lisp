;;;; CRAM-OBJECT-KNOWLEDGE (OBJECTS): grasps, gripper openings and efforts of the household
;;;; and shop objects, in the tables of MAN-INT.

(defpackage :cram-object-knowledge
  (:nicknames :objects)
  (:use :cl)
  (:export #:*bottle-grasp-xy-offset* #:*bottle-grasp-z-offset* #:*pregrasp-back*
           #:*pregrasp-up* #:*lift-z* #:household-object-types))

(in-package :cram-object-knowledge)

(defparameter *bottle-grasp-xy-offset* 0.02
  "Metres between a bottle's axis and the tool frame of a side grasp, towards the gripper.")
(defparameter *bottle-grasp-z-offset* 0.005
  "Metres the tool frame of a bottle grasp lies above the bottle's origin.")
(defparameter *pregrasp-back* 0.15 "Metres a pregrasp pose lies back against the approach.")
(defparameter *pregrasp-up* 0.07 "Metres the first pregrasp pose lies above the grasp height.")
(defparameter *lift-z* 0.07 "Metres of each of the two lifting steps.")

;;; Object types: everything is a household item; shop products are household items too.
;;; The kitchen's household types (cup, bowl, cutlery, milk, cereal ...) and their grasps are
;;; in src/object-knowledge/ (system cram-plans/cram-household-knowledge).
(man-int:define-object-type :household-item)
(man-int:define-object-type :bottle :household-item)
(man-int:define-object-type :somat :household-item)
(man-int:define-object-type :denkmit :household-item)

(defun household-object-types ()
  "The household object types: every declared subtype of :HOUSEHOLD-ITEM."
  (remove-if-not (lambda (type) (and (not (eq type :household-item))
                                     (man-int:object-type-subtype-p :household-item type)))
                 (man-int:known-object-types)))

;;; Gripping: default effort 50 and opening 0.10 m.
(man-int:define-object-type-gripping :household-item :effort 50 :opening 0.1)
(man-int:define-object-type-gripping :bottle :effort 50 :opening 0.1 :rotationally-symmetric t)

;;; Side, front and back grasps: the gripper moves horizontally onto the object with its z
;;; axis up; the tool frame x axis points along the approach.
(defmacro def-side-grasps (types xy z &key (sides '(:left-side :right-side :back :front)))
  `(progn
     ,@(loop for side in sides
             collect
             (destructuring-bind (translation rotation approach)
                 (ecase side
                   (:left-side `((0 ,xy ,z) (0 0 -0.7071067811865476d0 0.7071067811865476d0) (0 -1 0)))
                   (:right-side `((0 ,(- xy) ,z) (0 0 0.7071067811865476d0 0.7071067811865476d0) (0 1 0)))
                   (:back `((,(- xy) 0 ,z) (0 0 0 1) (1 0 0)))
                   (:front `((,xy 0 ,z) (0 0 1 0) (-1 0 0))))
               `(man-int:def-object-type-to-gripper-transforms ,types :all ,side
                  :grasp-translation ,translation :grasp-rotation ,rotation
                  :approach ,approach :pregrasp-back *pregrasp-back*
                  :pregrasp-up *pregrasp-up* :lift *lift-z*)))))

;; Bottles have no top grasp.
(def-side-grasps :bottle 0.02 0.005)
(def-side-grasps (:somat :denkmit) 0.01 0.0)
