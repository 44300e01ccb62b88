;;;; The ROS node of a cram-plans image: STARTUP-ROS starts it and runs the registered init
;;;; functions, SHUTDOWN-ROS runs the cleanup functions and stops it.

(in-package :roslisp-utilities)

(defvar *belief-state-publish-rate* 10
  "How often (Hz) STARTUP-ROS's background thread publishes the belief state; NIL: never (call
PUBLISH-BELIEF-STATE yourself).")

(defvar *ros-init-functions* '()
  "Names (symbols) of the functions STARTUP-ROS calls, in registration order. Bind it to run
STARTUP-ROS with a different set.")

(defvar *ros-cleanup-functions* '()
  "Names (symbols) of the functions SHUTDOWN-ROS calls, in registration order.")

(defun check-function-name (name what)
  (unless (and name (symbolp name))
    (ros-fail "~a: ~s, expected the name (a non-NIL symbol) of a function of no arguments" what name))
  name)

(defun add-function-name (name list)
  "LIST with NAME appended, unless NAME is already in it (then LIST keeps its order)."
  (if (member name list) list (append list (list name))))

(defmacro register-ros-init-function (name)
  "Register the function named NAME (an unquoted symbol) to be called, with no arguments, by
STARTUP-ROS after the node has started. Functions run in registration order; registering a name
again keeps its place. The function is called through its name, so redefinitions take effect."
  `(setf *ros-init-functions*
         (add-function-name (check-function-name ',name 'register-ros-init-function)
                            *ros-init-functions*)))

(defmacro register-ros-cleanup-function (name)
  "Register the function named NAME (an unquoted symbol) to be called, with no arguments, by
SHUTDOWN-ROS before the node stops. Functions run in registration order."
  `(setf *ros-cleanup-functions*
         (add-function-name (check-function-name ',name 'register-ros-cleanup-function)
                            *ros-cleanup-functions*)))

(defun unregister-ros-init-function (name)
  "Remove NAME from the init functions; true when it was registered."
  (check-function-name name 'unregister-ros-init-function)
  (prog1 (and (member name *ros-init-functions*) t)
    (setf *ros-init-functions* (remove name *ros-init-functions*))))

(defun unregister-ros-cleanup-function (name)
  "Remove NAME from the cleanup functions; true when it was registered."
  (check-function-name name 'unregister-ros-cleanup-function)
  (prog1 (and (member name *ros-cleanup-functions*) t)
    (setf *ros-cleanup-functions* (remove name *ros-cleanup-functions*))))

(defun ros-init-functions ()
  "The names of the registered init functions, in the order STARTUP-ROS calls them."
  (copy-list *ros-init-functions*))

(defun ros-cleanup-functions ()
  "The names of the registered cleanup functions, in the order SHUTDOWN-ROS calls them."
  (copy-list *ros-cleanup-functions*))

(defun ros-running-p ()
  "True while this image's ROS node runs."
  (eq (roslisp:node-status) :running))

(defun check-node-name (name)
  (unless (and (stringp name) (plusp (length name)) (alpha-char-p (char name 0))
               (every (lambda (c) (or (alphanumericp c) (char= c #\_))) name))
    (ros-fail "STARTUP-ROS: node name ~s, expected a string of letters, digits and underscores ~
               starting with a letter (e.g. \"cram_plans\")" name))
  name)

(defun call-registered (names kind)
  "Call each function of NAMES; an undefined one is an error naming it and KIND."
  (dolist (name names)
    (unless (fboundp name)
      (ros-fail "~a function ~s is registered but not defined" kind name))
    (roslisp:ros-debug (roslisp-utilities) "Running ~a function ~s" kind name)
    (funcall name)))

(defun startup-ros (&key (name "cram_plans") anonymous master-uri
                      (publish-rate *belief-state-publish-rate*))
  "Start this image's ROS node NAME (with a unique suffix when ANONYMOUS) on the master at
MASTER-URI (a string http://HOST:PORT; default $ROS_MASTER_URI, see ROS-MASTER-URI), call the
registered init functions in order, then start the belief-state publisher at PUBLISH-RATE Hz
(NIL: publish only on demand, through PUBLISH-BELIEF-STATE). A running node is shut down first.
When no master answers within 3 s, signals ROS-MASTER-UNREACHABLE naming the URI and
ROS_MASTER_URI, without starting anything. Returns the node's name."
  (check-node-name name)
  (check-publish-rate publish-rate)
  (multiple-value-bind (uri source) (ros-master-uri master-uri)
    (multiple-value-bind (host port) (parse-master-uri uri)
      (declare (ignore port))
      (unless (ros-available-p :master-uri uri :timeout 3)
        (error 'ros-master-unreachable :uri uri :source source))
      (when (ros-running-p) (shutdown-ros))
      (ensure-ros-home)
      (when (and (loopback-host-p host)
                 (null (uiop:getenv "ROS_IP")) (null (uiop:getenv "ROS_HOSTNAME")))
        (sb-posix:setenv "ROS_IP" "127.0.0.1" 1))
      (roslisp:start-ros-node name :master-uri uri :anonymous anonymous :cmd-line-args nil)
      (reset-publications)
      (call-registered *ros-init-functions* "ROS init")
      (when publish-rate
        (start-belief-state-publisher :rate publish-rate))
      roslisp::*ros-node-name*)))

(defun shutdown-ros ()
  "Stop the belief-state publisher, call the registered cleanup functions (an error in one is
logged and the others still run), and shut the node down. Does nothing when no node runs;
returns true when a node was stopped."
  (stop-belief-state-publisher)
  (when (ros-running-p)
    (dolist (name *ros-cleanup-functions*)
      (handler-case (if (fboundp name)
                        (funcall name)
                        (ros-fail "ROS cleanup function ~s is registered but not defined" name))
        (error (e)
          (roslisp:ros-error (roslisp-utilities) "Cleanup function ~s failed: ~a" name e))))
    (reset-publications)
    (roslisp:shutdown-ros-node)
    t))
