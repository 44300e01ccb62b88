;;;; BTR-UTILS: the tutorials' convenience functions on the current world.

(in-package :cram-bullet-reasoning-utilities)

(defun release-from-robots (object &optional (world btr:*current-bullet-world*))
  "Detach OBJECT (an object of WORLD) from every robot of WORLD that carries it, e.g. a bottle
left in the gripper by a failed run. Returns the robots it was taken from."
  (loop for o in (btr:objects world)
        when (and (typep o 'btr:robot-object) (btr:object-attached o object))
          do (btr:detach-object o object)
          and collect o))

(defun spawn-object (name type &key (world btr:*current-bullet-world*) (pose '((0 0 1) (0 0 0 1)))
                                     (color '(0.5 0.5 0.5) color-p) (mass 0.2) mesh)
  "Add an object NAME of the mesh TYPE (a keyword of BTR:*MESH-FILES*, e.g. :BOTTLE) at POSE, or
put it there afresh when it exists: released from any robot that holds it (a gripper of a
failed run), at rest, and recoloured when COLOR is given. Returns the object."
  (let ((existing (btr:object world name)))
    (cond ((null existing)
           (btr:add-object world :mesh name pose :mesh (or mesh type) :mass mass :color color
                                                  :types (list type)))
          ((not (typep existing 'btr:item))
           (error 'btr:btr-error
                  :message (format nil "SPAWN-OBJECT: ~s names a ~(~a~) of the world, not a ~
                                        movable object; choose another name"
                                   name (type-of existing))))
          ((not (member type (btr::item-types existing)))
           ;; another kind of object under that name: make it anew
           (release-from-robots existing world)
           (btr:remove-object world name)
           (btr:add-object world :mesh name pose :mesh (or mesh type) :mass mass :color color
                                                  :types (list type)))
          (t
           (release-from-robots existing world)
           (setf (btr:pose existing) pose)
           (cram-native:set-body-velocity (btr::world-handle world) (btr:object-handle existing)
                                          #(0d0 0d0 0d0 0d0 0d0 0d0))
           (when color-p
             (cram-native:set-object-color (btr::world-handle world) (btr:object-handle existing)
                                           (btr::color-rgba color) -1))
           existing))))

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
