;;;; Small helpers the seed scripts' checks share: the current world, coordinates, tolerances and
;;;; Prolog answers, with names read the way the pages' code reads them.

(in-package :cram-plans-seeds)

(defun world () "The current belief state." btr:*current-bullet-world*)

(defun tut (name)
  "NAME as the tutorial pages' code reads it: in BTW-TUT (keywords stay keywords)."
  (if (keywordp name) name (intern (symbol-name name) "BTW-TUT")))

(defun robot-object () "The robot of the current world." (btr:get-robot-object))

(defun xyz (pose)
  "The position of POSE as a list (x y z)."
  (let ((o (cl-transforms:origin pose)))
    (list (cl-transforms:x o) (cl-transforms:y o) (cl-transforms:z o))))

(defun yaw (pose) "The yaw of POSE." (cl-transforms:get-yaw (cl-transforms:orientation pose)))

(defun near (a b tol)
  "True when the lists of numbers A and B agree element by element within TOL."
  (every (lambda (x y) (<= (abs (- x y)) tol)) a b))

(defun binding (name answer)
  "The value of the variable called NAME (any package) in the Prolog ANSWER."
  (cdr (find name answer :key (lambda (b) (and (symbolp (car b)) (symbol-name (car b)))) :test #'equal)))
