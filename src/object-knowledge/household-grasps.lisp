;;;; Grasps of the household types with CRAM's numbers: the tool frame in the object frame
;;;; (translation and rotation matrix), two pregrasp offsets in the object frame, and the lift
;;;; offset in the robot base frame; bowls in drawers and cutlery on shelves have their own
;;;; pregrasp and lift.

(in-package :cram-object-knowledge)

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defparameter *grasp-rotations*
    '((:zy (1 0 0) (0 -1 0) (0 0 -1))
      (:zx (0 1 0) (1 0 0) (0 0 -1))
      (:xz (0 0 -1) (-1 0 0) (0 1 0))
      (:xz2 (0 0 -1) (1 0 0) (0 -1 0))
      (:-xz (0 0 1) (1 0 0) (0 1 0))
      (:-xz2 (0 0 1) (-1 0 0) (0 -1 0))
      (:yz (1 0 0) (0 0 -1) (0 1 0))
      (:-yz (-1 0 0) (0 0 1) (0 1 0))
      (:yzf (-1 0 0) (0 0 -1) (0 -1 0))
      (:-yzf (1 0 0) (0 0 1) (0 -1 0))
      (:yx (0 1 0) (0 0 -1) (-1 0 0))
      (:xy (0 0 -1) (0 -1 0) (-1 0 0)))
    "Named tool-frame rotations in the object frame, as rotation matrix rows: :ZY is the
gripper's z axis along the object's -z (from the top), :XZ along its -x (from the front) ...")

  (defparameter *z-forward-to-tool-frame*
    '((0 1 0) (0 0 1) (1 0 0))
    "The rotation from a gripper frame with z forward between the fingers (the frame the rows of
*GRASP-ROTATIONS* are written in) to the tool frame of the robots here, with x forward.")

  (defun grasp-rotation-rows (name)
    "The rotation matrix rows of the tool frame in the object frame for the grasp rotation NAME
(a key of *GRASP-ROTATIONS*, written for a z-forward gripper frame)."
    (let ((rows (or (cdr (assoc name *grasp-rotations*))
                    (error "Unknown grasp rotation ~s: expected one of ~{~s~^ ~}." name
                           (mapcar #'car *grasp-rotations*)))))
      (loop for row in rows
            collect (loop for j below 3
                          collect (loop for k below 3
                                        sum (* (nth k row) (nth j (nth k *z-forward-to-tool-frame*))))))))

  (defun exact-doubles (tree)
    "TREE with every real replaced by the double-float of its decimal value (0.07 -> 0.07d0)."
    (cond ((realp tree) (float (rationalize tree) 1d0))
          ((consp tree) (cons (exact-doubles (car tree)) (exact-doubles (cdr tree))))
          (t tree))))


(defmacro def-household-grasps (types &body grasps)
  "Declare for TYPES (keywords) the GRASPS, each (grasp translation rotation-name
pregrasp-offsets lift-offset &key location-type), for both arms."
  `(progn
     ,@(loop for (grasp translation rotation offsets lift . keys) in grasps
             collect `(man-int:def-object-type-to-gripper-transforms ,types :all ,grasp
                        :grasp-translation ,(exact-doubles translation)
                        :grasp-rotation ,(and rotation (grasp-rotation-rows rotation))
                        :pregrasp-offsets ,(exact-doubles offsets)
                        :lift-offset ,(exact-doubles lift) ,@keys))))

;;; Cups: from the top (two ways across the rim), from the sides, front and back.
(def-household-grasps (:cup)
  (:top (-0.05 0 0.04) :zy ((0 0 0.07)) (0 0 0.07))
  (:top2 (0 -0.05 0.04) :zx ((0 0 0.07)) (0 0 0.07))
  (:left-side (0 -0.02 0.01) :yzf ((0 0.15 0.07) (0 0.15 0)) (0 0 0.07))
  (:right-side (0 0.02 0.01) :-yzf ((0 -0.15 0.07) (0 -0.15 0)) (0 0 0.07))
  (:back (0.02 0 0.01) :-xz2 ((-0.15 0 0.07) (-0.15 0 0)) (0 0 0.07))
  (:front (-0.02 0 0.01) :xz ((0.15 0 0.07) (0.15 0 0)) (0 0 0.07)))

;;; Bowls: the rim from the top at four places; out of a drawer from higher up.
(def-household-grasps (:bowl)
  (:top (-0.08 0 0.02) :zy ((0 0 0.07)) (0 0 0.07))
  (:top-front (0.08 0 0.02) :zy ((0 0 0.07)) (0 0 0.07))
  (:top-left (0 0.08 0.02) :zx ((0 0 0.07)) (0 0 0.07))
  (:top-right (0 -0.08 0.02) :zx ((0 0 0.07)) (0 0 0.07)))

(def-household-grasps (:bowl)
  (:top nil nil ((0 0 0.2)) (0 0 0.2) :location-type :drawer)
  (:top-front nil nil ((0 0 0.2)) (0 0 0.2) :location-type :drawer)
  (:top-left nil nil ((0 0 0.2)) (0 0 0.2) :location-type :drawer)
  (:top-right nil nil ((0 0 0.2)) (0 0 0.2) :location-type :drawer))

;;; Cutlery: from the top, or pushed at from the front; on a shelf from less high.
(def-household-grasps (:cutlery)
  (:top (0 0 -0.015) :zx ((0 0 0.2)) (0 0 0.2))
  (:front (-0.03 0 0) :yx ((-0.03 0 0)) (-0.03 0 0)))

(def-household-grasps (:cutlery)
  (:top nil nil ((0 0 0.07)) (0 0 0.07) :location-type :shelf))

;;; Milk cartons: from the four sides, lifted 0.15 m.
(def-household-grasps (:milk)
  (:front (-0.01 0 0.03) :xz ((0.15 0 0.15) (0.15 0 0)) (0 0 0.15))
  (:back (0.01 0 0.03) :-xz ((-0.15 0 0.15) (-0.15 0 0)) (0 0 0.15))
  (:left-side (0 -0.01 0.03) :yz ((0 0.15 0.15) (0 0.15 0)) (0 0 0.15))
  (:right-side (0 0.01 0.03) :-yz ((0 -0.15 0.15) (0 -0.15 0)) (0 0 0.15)))

;;; Cereal boxes: from the top, from the front and back, and front and back turned upside
;;; down (for a box that lies on its other side).
(def-household-grasps (:cereal)
  (:top (0 0 0.04) :zx ((0 0 0.07)) (0 0 0.07))
  (:front (0.015 0 0) :xz ((0.15 0 0.05) (0.15 0 0)) (0 0 0.1))
  (:back (-0.015 0 0) :-xz ((-0.15 0 0.05) (-0.15 0 0)) (0 0 0.1))
  (:front-flipped (0.015 0 0) :xz2 ((0.15 0 0.05) (0.15 0 0)) (0 0 0.1))
  (:back-flipped (-0.015 0 0) :-xz2 ((-0.15 0 0.05) (-0.15 0 0)) (0 0 0.1)))

;;; Out of a shelf, cereal boxes held from the front or back are lifted a little and pulled
;;; 0.4 m out before they go up.
(def-household-grasps (:cereal)
  (:front nil nil ((0.15 0 0.05) (0.15 0 0)) ((0.015 0 0.06) (0.4 0 0.06)) :location-type :shelf)
  (:back nil nil ((-0.15 0 0.05) (-0.15 0 0)) ((-0.015 0 0.06) (-0.4 0 0.06)) :location-type :shelf))
