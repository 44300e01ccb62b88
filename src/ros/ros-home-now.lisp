;;;; Loaded before roslisp (system roslisp-utilities/ros-home): make the ROS home directory.

(in-package :roslisp-utilities)

(ensure-ros-home)

;; roslisp's loader is about to define ROS-LOAD:LOAD-SYSTEM over this project's one; take ours
;; away first, so that it defines a fresh function (no redefinition warning), and node.lisp,
;; loaded after roslisp, wraps roslisp's again
(let ((name (and (find-package :ros-load-manifest)
                 (find-symbol "LOAD-SYSTEM" :ros-load-manifest))))
  (when (and name (fboundp name) (not (asdf:component-loaded-p "ros-load-manifest")))
    (fmakunbound name)))
