;;;; The node's life cycle as seen from images without roslisp: init and cleanup function
;;;; registries, whether a node runs, logging, and STARTUP-ROS / SHUTDOWN-ROS and the publisher
;;;; calls, which load the roslisp part (system roslisp-utilities/ros) when it is needed.

(in-package :roslisp-utilities)

(defvar *belief-state-publish-rate* 10
  "How often (Hz) STARTUP-ROS's background thread publishes the belief state; NIL: never (call
PUBLISH-BELIEF-STATE yourself).")

;;; Both registries are hash tables keyed by function name, as in CRAM (so
;;; (alexandria:hash-table-keys roslisp-utilities:*ros-init-functions*) lists the names); the value
;;; of a name is the name itself, which FUNCALL calls through its current definition. The order
;;; STARTUP-ROS / SHUTDOWN-ROS call them in is the registration order, kept beside each table (in
;;; *REGISTRATION-ORDERS*), so binding the variable to a fresh table gives a fresh order too.
;;; For compatibility with code written against the earlier registry, a variable bound to a list
;;; of names is still accepted: that list is the set and the order.

(defvar *registration-orders* (make-hash-table :test 'eq :weakness :key)
  "Registration order (a list of names) of each registry hash table.")

(defun make-function-registry (&rest names)
  "A fresh registry (hash table) holding NAMES, registered in that order."
  (let ((table (make-hash-table :test 'eq)))
    (dolist (name names table) (registry-add name table))))

(defvar *ros-init-functions* (make-function-registry)
  "The functions STARTUP-ROS calls: a hash table from function name (a symbol) to that name,
called in registration order. Bind it (e.g. to (MAKE-FUNCTION-REGISTRY 'A 'B), or to a list of
names in calling order) to run STARTUP-ROS with a different set.")

(defvar *ros-cleanup-functions* (make-function-registry)
  "The functions SHUTDOWN-ROS calls: a hash table from function name to that name, called in
registration order.")

(defun check-function-name (name what)
  (unless (and name (symbolp name))
    (ros-fail "~a: ~s, expected the name (a non-NIL symbol) of a function of no arguments" what name))
  name)

(defun check-registry (registry what)
  (unless (or (hash-table-p registry) (listp registry))
    (ros-fail "~a is ~s, expected a hash table from function names to functions (or a list of names)"
              what registry))
  registry)

(defun registry-names (registry)
  "The names in REGISTRY in calling (registration) order: for a hash table its recorded order,
followed by any key put in by hand (SETF GETHASH), in the table's own order; a list is its own order."
  (if (listp registry)
      (remove-duplicates registry :from-end t)
      (let* ((order (remove-if-not (lambda (n) (nth-value 1 (gethash n registry)))
                                   (gethash registry *registration-orders*)))
             (extra '()))
        (maphash (lambda (k v) (declare (ignore v)) (unless (member k order) (push k extra))) registry)
        (append order (nreverse extra)))))

(defun registry-add (name registry)
  "REGISTRY with NAME registered (a name registered again keeps its place)."
  (cond ((listp registry) (if (member name registry) registry (append registry (list name))))
        (t (unless (nth-value 1 (gethash name registry))
             (setf (gethash registry *registration-orders*)
                   (append (remove name (gethash registry *registration-orders*)) (list name))))
           (setf (gethash name registry) name)
           registry)))

(defun registry-remove (name registry)
  "(values REGISTRY-without-NAME was-registered-p)."
  (if (listp registry)
      (values (remove name registry) (and (member name registry) t))
      (let ((present (nth-value 1 (gethash name registry))))
        (remhash name registry)
        (setf (gethash registry *registration-orders*)
              (remove name (gethash registry *registration-orders*)))
        (values registry present))))

(defmacro register-ros-init-function (name)
  "Register the function named NAME (an unquoted symbol) to be called, with no arguments, by
STARTUP-ROS after the node has started. Functions run in registration order; registering a name
again keeps its place. The function is called through its name, so redefinitions take effect."
  `(setf *ros-init-functions*
         (registry-add (check-function-name ',name 'register-ros-init-function)
                       (check-registry *ros-init-functions* '*ros-init-functions*))))

(defmacro register-ros-cleanup-function (name)
  "Register the function named NAME (an unquoted symbol) to be called, with no arguments, by
SHUTDOWN-ROS before the node stops. Functions run in registration order."
  `(setf *ros-cleanup-functions*
         (registry-add (check-function-name ',name 'register-ros-cleanup-function)
                       (check-registry *ros-cleanup-functions* '*ros-cleanup-functions*))))

(defun unregister-ros-init-function (name)
  "Remove NAME from the init functions; true when it was registered."
  (check-function-name name 'unregister-ros-init-function)
  (multiple-value-bind (registry present)
      (registry-remove name (check-registry *ros-init-functions* '*ros-init-functions*))
    (setf *ros-init-functions* registry)
    present))

(defun unregister-ros-cleanup-function (name)
  "Remove NAME from the cleanup functions; true when it was registered."
  (check-function-name name 'unregister-ros-cleanup-function)
  (multiple-value-bind (registry present)
      (registry-remove name (check-registry *ros-cleanup-functions* '*ros-cleanup-functions*))
    (setf *ros-cleanup-functions* registry)
    present))

(defun ros-init-functions ()
  "The names of the registered init functions, in the order STARTUP-ROS calls them (a fresh list)."
  (copy-list (registry-names (check-registry *ros-init-functions* '*ros-init-functions*))))

(defun ros-cleanup-functions ()
  "The names of the registered cleanup functions, in the order SHUTDOWN-ROS calls them (a fresh list)."
  (copy-list (registry-names (check-registry *ros-cleanup-functions* '*ros-cleanup-functions*))))

;;; ---- hooks the roslisp part installs ---------------------------------------------------------------

(defvar *node-status-function* nil
  "Function of no arguments giving roslisp's node status (:RUNNING, :SHUTDOWN ...); NIL until
the roslisp part is loaded.")

(defvar *parameter-reader* nil
  "Function of a parameter name returning (values value present-p fully-qualified-name) from the
running node's master; NIL until the roslisp part is loaded.")

(defvar *log-function* nil
  "Function of a level (:debug :info :warn :error) and a message string that logs through
roslisp; NIL until the roslisp part is loaded.")

(defun ros-running-p ()
  "True while this image's ROS node runs."
  (and *node-status-function* (eq (funcall *node-status-function*) :running)))

(defun ros-log (level fmt &rest args)
  "Log the formatted message at LEVEL (:debug :info :warn :error) under the name
ROSLISP-UTILITIES: through roslisp (stdout and /rosout) when it is loaded, else on stdout in
roslisp's shape."
  (let ((text (apply #'format nil fmt args)))
    (if *log-function*
        (funcall *log-function* level text)
        (unless (eq level :debug)
          (format t "~&[(ROSLISP-UTILITIES) ~a] ~,3f: ~a~%" level
                  (/ (- (get-universal-time) #.(encode-universal-time 0 0 0 1 1 1970 0)) 1d0) text)
          (force-output)))))

;;; ---- calls that need the roslisp part ---------------------------------------------------------------

(defun ensure-roslisp-part ()
  "Load the system roslisp-utilities/ros (roslisp and the message systems) unless it is loaded."
  (unless *node-status-function*
    (unless (asdf:find-system "roslisp" nil)
      (ros-fail "STARTUP-ROS needs roslisp, and ASDF finds no system \"roslisp\": install the ~
                 Debian package roslisp (make setup does), or add its directory to ASDF's ~
                 source registry"))
    (handler-bind ((warning #'muffle-warning))
      (asdf:load-system "cram-plans/roslisp-utilities/ros")))
  t)

(defun check-node-name (name)
  (unless (and (stringp name) (plusp (length name)) (alpha-char-p (char name 0))
               (every (lambda (c) (or (alphanumericp c) (char= c #\_))) name))
    (ros-fail "STARTUP-ROS: node name ~s, expected a string of letters, digits and underscores ~
               starting with a letter (e.g. \"cram_plans\")" name))
  name)

(defun check-publish-rate (rate)
  (unless (or (null rate) (and (realp rate) (> rate 0) (<= rate 1000)))
    (ros-fail "belief state publish rate ~s, expected NIL or a number of Hz in (0, 1000]" rate))
  rate)

(defun startup-ros (&key (name "cram_plans") anonymous master-uri
                      (publish-rate *belief-state-publish-rate*) world)
  "Start this image's ROS node NAME (with a unique suffix when ANONYMOUS) on the master at
MASTER-URI (a string http://HOST:PORT; default $ROS_MASTER_URI, see ROS-MASTER-URI), call the
registered init functions in order, then start the belief-state publisher at PUBLISH-RATE Hz
(NIL: publish only on demand, through PUBLISH-BELIEF-STATE). A running node is shut down first.
Of the init functions that build a world (see REGISTER-ROS-WORLD), only the one of the world
the parameter server describes runs (kitchen_description: the kitchen with the PR2;
shelf_description: the shop with Pepper), or the one of WORLD (e.g. :KITCHEN) when given;
parameters that fit no world, or several, are a ROS-WORLD-ERROR naming them.
Loads roslisp (system roslisp-utilities/ros) on first use. When no master answers within 3 s,
signals ROS-MASTER-UNREACHABLE naming the URI and ROS_MASTER_URI, without starting or loading
anything. Returns the node's name."
  (check-node-name name)
  (check-publish-rate publish-rate)
  (when world (find-ros-world world))
  (multiple-value-bind (uri source) (ros-master-uri master-uri)
    (parse-master-uri uri)
    (unless (ros-available-p :master-uri uri :timeout 3)
      (error 'ros-master-unreachable :uri uri :source source))
    (ensure-roslisp-part)
    (uiop:symbol-call :roslisp-utilities '#:%startup-ros name anonymous uri publish-rate world)))

(defun shutdown-ros ()
  "Stop the belief-state publisher, call the registered cleanup functions (an error in one is
logged and the others still run), and shut the node down. Does nothing when no node runs;
returns true when a node was stopped."
  (when *node-status-function*
    (uiop:symbol-call :roslisp-utilities '#:%shutdown-ros)))

(defun publish-belief-state (&key (world btr:*current-bullet-world*) (markers t))
  "Publish WORLD's belief state once: its TF edges (BELIEF-STATE-TRANSFORMS) as one
tf2_msgs/TFMessage on *TF-TOPIC* and, when MARKERS, its items (BELIEF-STATE-MARKERS) as a
visualization_msgs/MarkerArray on *MARKER-TOPIC* (objects gone since the last call are deleted).
Needs a running node (STARTUP-ROS). Returns the numbers of transforms and markers published."
  (unless (ros-running-p)
    (ros-fail "PUBLISH-BELIEF-STATE needs a running ROS node; start one with ROSLISP-UTILITIES:STARTUP-ROS"))
  (check-world world)
  (uiop:symbol-call :roslisp-utilities '#:%publish-belief-state world markers))

(defun start-belief-state-publisher (&key (rate *belief-state-publish-rate*))
  "Publish the belief state (BTR:*CURRENT-BULLET-WORLD*'s global value, looked up each time) at
RATE Hz in a background thread until STOP-BELIEF-STATE-PUBLISHER or SHUTDOWN-ROS. A running
publisher is replaced. Errors while publishing are logged once per distinct message. Needs a
running node."
  (check-publish-rate rate)
  (unless rate (ros-fail "START-BELIEF-STATE-PUBLISHER: rate is NIL, expected a number of Hz"))
  (unless (ros-running-p)
    (ros-fail "START-BELIEF-STATE-PUBLISHER needs a running ROS node; start one with ROSLISP-UTILITIES:STARTUP-ROS"))
  (uiop:symbol-call :roslisp-utilities '#:%start-belief-state-publisher rate))

(defun stop-belief-state-publisher ()
  "Stop the background publisher and wait for its thread to end; true when one was running."
  (and *node-status-function*
       (uiop:symbol-call :roslisp-utilities '#:%stop-belief-state-publisher)))

(defun belief-state-publisher-running-p ()
  "True while the background belief-state publisher runs."
  (and *node-status-function*
       (uiop:symbol-call :roslisp-utilities '#:%belief-state-publisher-running-p)))
