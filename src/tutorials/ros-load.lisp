;;;; ROS-LOAD:LOAD-SYSTEM as the tutorials call it, (ros-load:load-system "cram_pepper_demo"
;;;; :cram-pepper-demo), mapped to this project's ASDF systems. The package is the one roslisp
;;;; names ROS-LOAD-MANIFEST (nickname ROS-LOAD), so that loading Debian's roslisp later finds it
;;;; and extends it instead of clashing with it.

(eval-when (:compile-toplevel :load-toplevel :execute)
  (unless (find-package :ros-load-manifest)
    (make-package :ros-load-manifest :nicknames '(:ros-load) :use '(:cl))
    (export (mapcar (lambda (name) (intern name :ros-load-manifest))
                    '("LOAD-SYSTEM" "*CURRENT-ROS-PACKAGE*"))
            :ros-load-manifest)))

(in-package :ros-load-manifest)

(defvar *current-ros-package* nil
  "The ROS package whose system LOAD-SYSTEM is loading.")

(defparameter *ros-package-systems*
  '(("cram_bullet_world_tutorial" . "cram-plans/cram-bullet-world-tutorial")
    ("cram_pepper_demo" . "cram-plans/cram-pepper-demo")
    ("cram_pepper_description" . "cram-plans/cram-pepper-description")
    ("cram_pr2_description" . "cram-plans/cram-pr2-description")
    ("cram_mobile_pick_place_plans" . "cram-plans/cram-mobile-pick-place-plans")
    ("cram_object_knowledge" . "cram-plans/cram-object-knowledge")
    ("cram_urdf_projection" . "cram-plans/cram-urdf-projection")
    ("cram_bullet_reasoning" . "cram-plans/cram-bullet-reasoning"))
  "ROS package name → the ASDF system that provides it in cram-plans.")

(defun ros-package-system-name (ros-package)
  "The ASDF system name for the ROS package ROS-PACKAGE (underscores read as hyphens)."
  (unless (and (stringp ros-package) (plusp (length ros-package)))
    (error "ROS-LOAD: expected a ROS package name string such as \"cram_pepper_demo\", got ~s."
           ros-package))
  (or (cdr (assoc ros-package *ros-package-systems* :test #'string=))
      (substitute #\- #\_ (string-downcase ros-package))))

(unless (fboundp 'load-system)
  (defun load-system (ros-package &optional system force)
    "Load the ASDF SYSTEM (a symbol or string) of the ROS package ROS-PACKAGE; without SYSTEM
the one ROS-PACKAGE maps to. FORCE recompiles. Returns the system's name."
    (let ((name (cond ((null system) (ros-package-system-name ros-package))
                      ((symbolp system) (string-downcase (symbol-name system)))
                      ((stringp system) system)
                      (t (error "ROS-LOAD:LOAD-SYSTEM: expected a system name, got ~s." system))))
          (*current-ros-package* ros-package))
      (ros-package-system-name ros-package)
      ;; this project's systems live in cram-plans.asd as cram-plans/NAME
      (unless (asdf:find-system name nil)
        (let ((ours (concatenate 'string "cram-plans/" name)))
          (when (asdf:find-system ours nil) (setf name ours))))
      (unless (asdf:find-system name nil)
        (error "ROS-LOAD:LOAD-SYSTEM: no ASDF system ~s for the ROS package ~s." name ros-package))
      (asdf:load-system name :force force)
      name)))
