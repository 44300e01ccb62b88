;;;; The roslisp part of the node's life cycle: starting and stopping roslisp's node, and the
;;;; hooks through which the rest of roslisp-utilities reads parameters and logs.

(in-package :roslisp-utilities)

;; roslisp has just (re)defined ROS-LOAD:LOAD-SYSTEM; this project's loader wraps it again
(ros-load-manifest::install-cram-plans-load-system)

;; roslisp's loader (ros-load-manifest) adds PERFORM :AROUND methods on (COMPILE-OP T) and
;; (LOAD-OP T) to every Lisp file ASDF handles afterwards: a marker file per component *name* in
;; $ROS_HOME, waited on while it exists. It was written for catkin workspaces compiled by several
;; processes; here it makes unrelated files of the same name (every "package.lisp") wait for each
;; other across images sharing a ROS_HOME, and a marker left by a killed compile blocks every later
;; load of a file of that name forever. ASDF already writes fasls atomically (temporary file, then
;; rename), so the methods are removed.
(defun remove-roslisp-asdf-markers ()
  "Remove ros-load-manifest's marker-file PERFORM :AROUND methods; returns how many were removed."
  (let ((count 0))
    (dolist (op '(asdf:compile-op asdf:load-op) count)
      (let ((method (find-method #'asdf:perform '(:around) (list (find-class op) (find-class t)) nil)))
        (when method
          (remove-method #'asdf:perform method)
          (incf count))))))

(remove-roslisp-asdf-markers)

(defun roslisp-log (level text)
  "Log TEXT at LEVEL through roslisp's macros (stdout, and /rosout while a node runs)."
  (ecase level
    (:debug (roslisp:ros-debug (roslisp-utilities) "~a" text))
    (:info (roslisp:ros-info (roslisp-utilities) "~a" text))
    (:warn (roslisp:ros-warn (roslisp-utilities) "~a" text))
    (:error (roslisp:ros-error (roslisp-utilities) "~a" text))))

(defun roslisp-read-parameter (name)
  "(values value present-p fully-qualified-name) of the parameter NAME on the node's master."
  (let ((full (roslisp::fully-qualified-name name)))
    (if (roslisp:has-param name)
        (values (roslisp:get-param name) t full)
        (values nil nil full))))

(setf *node-status-function* #'roslisp:node-status
      *parameter-reader* #'roslisp-read-parameter
      *log-function* #'roslisp-log)

(defun call-registered (names kind)
  "Call each function of NAMES; an undefined one is an error naming it and KIND."
  (dolist (name names)
    (unless (fboundp name)
      (ros-fail "~a function ~s is registered but not defined" kind name))
    (ros-log :debug "Running ~a function ~s" kind name)
    (funcall name)))

(defun %startup-ros (name anonymous uri publish-rate world)
  "STARTUP-ROS once a master answers at URI and roslisp is loaded."
  (multiple-value-bind (host port) (parse-master-uri uri)
    (declare (ignore port))
    (when (ros-running-p) (shutdown-ros))
    (ensure-ros-home)
    (when (and (loopback-host-p host)
               (null (uiop:getenv "ROS_IP")) (null (uiop:getenv "ROS_HOSTNAME")))
      (sb-posix:setenv "ROS_IP" "127.0.0.1" 1))
    (roslisp:start-ros-node name :master-uri uri :anonymous anonymous :cmd-line-args nil)
    (reset-publications)
    (call-registered (select-init-functions (ros-init-functions) #'roslisp-read-parameter
                                            :world world)
                     "ROS init")
    (when publish-rate
      (start-belief-state-publisher :rate publish-rate))
    roslisp::*ros-node-name*))

(defun %shutdown-ros ()
  "SHUTDOWN-ROS with roslisp loaded."
  (%stop-belief-state-publisher)
  (when (ros-running-p)
    (dolist (name (ros-cleanup-functions))
      (handler-case (if (fboundp name)
                        (funcall name)
                        (ros-fail "ROS cleanup function ~s is registered but not defined" name))
        (error (e) (ros-log :error "Cleanup function ~s failed: ~a" name e))))
    (reset-publications)
    (roslisp:shutdown-ros-node)
    t))
