;;;; ROS_HOME must exist before roslisp is loaded: roslisp's ASDF extension creates a lock file
;;;; there for every file it compiles and waits forever when it cannot. ros-home-now.lisp
;;;; (system roslisp-utilities/ros-home) calls ENSURE-ROS-HOME before roslisp loads.

(in-package :roslisp-utilities)

(defun ros-home-directory ()
  "The directory ROS tools and roslisp write to: $ROS_HOME, or ~/.ros/ when it is unset or empty."
  (let ((env (uiop:getenv "ROS_HOME")))
    (if (and env (plusp (length env)))
        (uiop:ensure-directory-pathname env)
        (merge-pathnames (make-pathname :directory '(:relative ".ros")) (user-homedir-pathname)))))

(defun ensure-ros-home ()
  "Create the ROS home directory (see ROS-HOME-DIRECTORY) and its log/ subdirectory when missing;
return the home directory. An error names the directory when it cannot be created."
  (let ((dir (ros-home-directory)))
    (handler-case (ensure-directories-exist (merge-pathnames "log/" dir))
      (file-error (e)
        (error "ROS home directory ~a (from ~:[~~/.ros~;$ROS_HOME~]) cannot be created: ~a"
               dir (uiop:getenv "ROS_HOME") e)))
    dir))

