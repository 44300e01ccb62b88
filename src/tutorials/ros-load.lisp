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

(defun ros-package-system-name (ros-package)
  "The ASDF system name for the ROS package ROS-PACKAGE (underscores read as hyphens); this
project provides it as cram-plans/NAME."
  (unless (and (stringp ros-package) (plusp (length ros-package)))
    (error "ROS-LOAD: expected a ROS package name string such as \"cram_pepper_demo\", got ~s."
           ros-package))
  (substitute #\- #\_ (string-downcase ros-package)))

(defvar *roslisp-load-system* nil
  "roslisp's own LOAD-SYSTEM (it finds packages with rospack), kept for the ROS packages this
project does not provide; NIL when roslisp's loader is not loaded.")

(defun cram-plans-load-system (ros-package &optional system force)
  "Load the ASDF SYSTEM (a symbol or string) of the ROS package ROS-PACKAGE; without SYSTEM
the one ROS-PACKAGE maps to. FORCE recompiles. Returns the system's name. A package this project
does not provide is handed to roslisp's loader when it is loaded."
  (let* ((default (ros-package-system-name ros-package))
         (name (cond ((null system) default)
                     ((symbolp system) (string-downcase (symbol-name system)))
                     ((stringp system) system)
                     (t (error "ROS-LOAD:LOAD-SYSTEM: expected a system name, got ~s." system))))
         ;; this project's systems live in cram-plans.asd as cram-plans/NAME; look them up and
         ;; load them with no current ROS package, so that roslisp's search (rospack) stays out
         (*current-ros-package* nil)
         (found (find-if (lambda (n) (asdf:find-system n nil))
                         (list (concatenate 'string "cram-plans/" name) name))))
    (cond (found
           (asdf:load-system found :force force)
           found)
          (*roslisp-load-system*
           (funcall *roslisp-load-system* ros-package (or system ros-package) force))
          (t
           (error "ROS-LOAD:LOAD-SYSTEM: no ASDF system ~s for the ROS package ~s."
                  name ros-package)))))

(defun install-cram-plans-load-system ()
  "Make ROS-LOAD:LOAD-SYSTEM this project's loader, keeping roslisp's when it was defined (roslisp
defines the same function when it loads: STARTUP-ROS calls this again after loading roslisp)."
  (let ((current (and (fboundp 'load-system) (fdefinition 'load-system))))
    (unless (and current
                 (eq (nth-value 2 (function-lambda-expression current)) 'cram-plans-load-system))
      (when current (setf *roslisp-load-system* current))
      (setf (fdefinition 'load-system) #'cram-plans-load-system
            (documentation 'load-system 'function) (documentation 'cram-plans-load-system 'function))))
  'load-system)

(install-cram-plans-load-system)
