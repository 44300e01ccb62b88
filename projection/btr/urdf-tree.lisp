;;;; Walking a parsed URDF's tree: joints in document order, descendants, the handle of a part
;;;; and the joint that moves it (the lookups containers are found by).

(in-package :cl-urdf)

(defun child-joints-in-order (link)
  "The child joints of LINK in URDF document order."
  (reverse (child-joints link)))

(defun movable-joint-p (joint)
  "True for a prismatic, revolute or continuous JOINT."
  (and (member (joint-type joint) '(:prismatic :revolute :continuous)) t))

(defun first-descendant-link (link predicate)
  "Depth first below LINK (excluded), in document order: the first link satisfying PREDICATE."
  (dolist (joint (child-joints-in-order link))
    (let ((child (child joint)))
      (when (funcall predicate child) (return child))
      (let ((below (first-descendant-link child predicate)))
        (when below (return below))))))

(defun first-descendant-joint (link predicate)
  "Depth first below LINK, in document order: the first joint satisfying PREDICATE."
  (dolist (joint (child-joints-in-order link))
    (when (funcall predicate joint) (return joint))
    (let ((below (first-descendant-joint (child joint) predicate)))
      (when below (return below)))))

(defun handle-name-p (link)
  (search "handle" (name link)))

(defun handle-link (link)
  "The handle of the part LINK: LINK itself when it is named *handle*, else the first link below
it so named; when that link has links below it, the first of those named *handle* (a tray's
handle bar, not its frame). NIL when there is none."
  (let ((handle (if (handle-name-p link) link (first-descendant-link link #'handle-name-p))))
    (and handle
         (or (first-descendant-link handle #'handle-name-p) handle))))

(defun connecting-joint (link)
  "The joint that moves the part LINK: the first movable joint below it (a fridge's main body →
its door's hinge), else the first movable joint above it (a drawer → its slide); NIL when none."
  (or (first-descendant-joint link #'movable-joint-p)
      (loop for joint = (parent-joint link) then (parent-joint (parent joint))
            while joint
            when (movable-joint-p joint) return joint)))
