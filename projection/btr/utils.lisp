;;;; BTR-UTILS: the tutorials' convenience functions on the current world.

(in-package :cram-bullet-reasoning-utilities)

(defun spawn-object (name type &key (world btr:*current-bullet-world*) (pose '((0 0 1) (0 0 0 1)))
                                     (color '(0.5 0.5 0.5)) (mass 0.2) mesh)
  "Add an object NAME of the mesh TYPE (a keyword of BTR:*MESH-FILES*, e.g. :BOTTLE) at POSE, or
move it there when it exists. Returns the object."
  (let ((existing (btr:object world name)))
    (if existing
        (progn (setf (btr:pose existing) pose) existing)
        (btr:add-object world :mesh name pose :mesh (or mesh type) :mass mass :color color
                                               :types (list type)))))

(defun move-object (name pose &optional (world btr:*current-bullet-world*))
  "Teleport the object NAME to POSE."
  (let ((o (object-instance name world)))
    (setf (btr:pose o) pose)
    o))

(defun kill-object (name &optional (world btr:*current-bullet-world*))
  "Remove the object NAME from the world."
  (btr:remove-object world name))

(defun kill-all-objects (&optional (world btr:*current-bullet-world*))
  "Remove every item (movable object) from the world; robots, environment and floor stay."
  (dolist (o (btr:objects world))
    (when (typep o 'btr:item)
      (btr:remove-object world (btr:name o)))))

(defun move-robot (pose &optional (world btr:*current-bullet-world*))
  "Teleport the robot to POSE."
  (let ((robot (or (btr:get-robot-object world)
                   (error "MOVE-ROBOT: there is no robot in the world"))))
    (setf (btr:pose robot) pose)
    robot))

(defun object-instance (name &optional (world btr:*current-bullet-world*))
  "The object NAME of the world, or an error naming it."
  (or (btr:object world name)
      (error 'btr:btr-error :message (format nil "there is no object ~s in the world" name))))

(defun object-pose (name &optional (world btr:*current-bullet-world*))
  "The pose of the object NAME."
  (btr:pose (object-instance name world)))
