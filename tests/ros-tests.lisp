;;;; Tests of the ROS integration (roslisp-utilities) that need no ROS master: names, init
;;;; functions, URDF fallbacks, the master probe, logging, and the belief state as TF and markers.

(defpackage :cram-plans-tests-ros
  (:use :cl :fiveam))

(in-package :cram-plans-tests-ros)

(def-suite ros :in cram-plans-tests:all
  :description "The ROS integration: node life cycle, URDFs from the parameter server, belief state on TF.")

(in-suite ros)

(defun repo-file (path) (asdf:system-relative-pathname "cram-plans/roslisp-utilities" path))

(defun free-port ()
  "A TCP port of 127.0.0.1 that nothing listens on now."
  (roslisp-utilities:free-local-port))

(defmacro with-env ((&rest bindings) &body body)
  "Run BODY with the environment variables of BINDINGS ((name value-or-nil) ...) set (NIL:
unset), restoring the previous values afterwards."
  (let ((saved (gensym "SAVED")))
    `(let ((,saved (mapcar (lambda (n) (cons n (uiop:getenv n))) (list ,@(mapcar #'first bindings)))))
       (unwind-protect
            (progn ,@(mapcar (lambda (b)
                               `(let ((v ,(second b)))
                                  (if v (sb-posix:setenv ,(first b) v 1) (sb-posix:unsetenv ,(first b)))))
                             bindings)
                   ,@body)
         (dolist (s ,saved)
           (if (cdr s) (sb-posix:setenv (car s) (cdr s) 1) (sb-posix:unsetenv (car s))))))))

(defun seconds-since (start)
  (/ (- (get-internal-real-time) start) internal-time-units-per-second))

;;; ---- names ---------------------------------------------------------------------------------------

(test ros-names
  (is (string= "bottle_1" (roslisp-utilities:rosify-underscores-lisp-name :bottle-1)))
  (is (string= "iai_kitchen" (roslisp-utilities:rosify-underscores-lisp-name "IAI-KITCHEN")))
  (is (string= "bottle-1" (roslisp-utilities:rosify-lisp-name 'bottle-1)))
  (is (eq :iai-kitchen (roslisp-utilities:lispify-ros-underscore-name "iai_kitchen")))
  (is (eq :fork-plastic (roslisp-utilities:lispify-ros-underscore-name
                         (roslisp-utilities:rosify-underscores-lisp-name :fork-plastic))))
  (is (eq :a-b (roslisp-utilities:lispify-ros-name "a-b")))
  (is (string= "bottle_2" (roslisp-utilities:object-frame-name :bottle-2)))
  (signals roslisp-utilities:ros-utilities-error (roslisp-utilities:rosify-underscores-lisp-name 42))
  (signals roslisp-utilities:ros-utilities-error (roslisp-utilities:rosify-lisp-name ""))
  (signals roslisp-utilities:ros-utilities-error (roslisp-utilities:lispify-ros-name nil)))

;;; ---- init and cleanup functions ------------------------------------------------------------------

(defun init-a () :a)
(defun init-b () :b)

(test ros-init-function-registry
  (let ((roslisp-utilities:*ros-init-functions* '())
        (roslisp-utilities:*ros-cleanup-functions* '()))
    (roslisp-utilities:register-ros-init-function init-b)
    (roslisp-utilities:register-ros-init-function init-a)
    (roslisp-utilities:register-ros-init-function init-b)
    (is (equal '(init-b init-a) (roslisp-utilities:ros-init-functions)))
    (roslisp-utilities:register-ros-cleanup-function init-a)
    (is (equal '(init-a) (roslisp-utilities:ros-cleanup-functions)))
    (is-true (roslisp-utilities:unregister-ros-init-function 'init-b))
    (is-false (roslisp-utilities:unregister-ros-init-function 'init-b))
    (is (equal '(init-a) (roslisp-utilities:ros-init-functions)))
    ;; the returned list is a copy
    (push 'other (cdr (roslisp-utilities:ros-init-functions)))
    (is (equal '(init-a) (roslisp-utilities:ros-init-functions)))
    (signals roslisp-utilities:ros-utilities-error
      (roslisp-utilities:register-ros-init-function nil))
    (signals roslisp-utilities:ros-utilities-error
      (roslisp-utilities:unregister-ros-cleanup-function "init-a"))))

;;; ---- URDFs without a node -------------------------------------------------------------------------

(test robot-description-fallback-without-node
  (is-false (roslisp-utilities:ros-running-p))
  (multiple-value-bind (text source)
      (roslisp-utilities:robot-description-string :fallback-file "robots/pr2/pr2.urdf")
    (is (string= (uiop:read-file-string (repo-file "robots/pr2/pr2.urdf")) text))
    (is (pathnamep source))
    (is (equal (truename (repo-file "robots/pr2/pr2.urdf")) source)))
  (multiple-value-bind (text source)
      (roslisp-utilities:robot-description-string
       :parameter "kitchen_description" :fallback-file (repo-file "resources/iai_kitchen.urdf"))
    (is (search "<robot name=\"iai_kitchen\"" text))
    (is (string= "iai_kitchen.urdf" (file-namestring source))))
  (let ((e (handler-case (roslisp-utilities:robot-description-string) (error (e) e))))
    (is (typep e 'roslisp-utilities:description-parameter-missing))
    (is (search "robot_description" (princ-to-string e)))
    (is (search "STARTUP-ROS" (princ-to-string e))))
  (let ((e (handler-case (roslisp-utilities:robot-description-string :fallback-file "robots/none.urdf")
             (error (e) e))))
    (is (typep e 'roslisp-utilities:ros-utilities-error))
    (is (search "none.urdf" (princ-to-string e))))
  ;; a file that is no URDF
  (signals roslisp-utilities:ros-utilities-error
    (roslisp-utilities:robot-description-string :fallback-file "resources/package.xml"))
  (signals roslisp-utilities:ros-utilities-error
    (roslisp-utilities:robot-description-string :parameter ""))
  (signals roslisp-utilities:ros-utilities-error
    (roslisp-utilities:robot-description-string :fallback-file 42)))

;; a fallback file is kept once read, and read again when it changes
(test robot-description-fallback-file-read-again-when-it-changes
  (let ((path (uiop:tmpize-pathname (merge-pathnames "cram-plans-fallback.urdf"
                                                     (uiop:temporary-directory)))))
    (flet ((write-urdf (name seconds-ago)
             (with-open-file (s path :direction :output :if-exists :supersede)
               (format s "<robot name=\"~a\"><link name=\"a\"/></robot>~%" name))
             ;; the write date as if written SECONDS-AGO
             (sb-posix:utime (namestring path) (- (get-universal-time) seconds-ago
                                                  (encode-universal-time 0 0 0 1 1 1970 0))
                             (- (get-universal-time) seconds-ago
                                (encode-universal-time 0 0 0 1 1 1970 0))))
           (read-urdf ()
             (roslisp-utilities:robot-description-string :parameter "no_such_parameter"
                                                         :fallback-file path)))
      (unwind-protect
           (progn
             (write-urdf "first" 60)
             (is (search "\"first\"" (read-urdf)))
             (is (eq (read-urdf) (read-urdf)))           ; kept
             (write-urdf "second" 30)                     ; another write date
             (is (search "\"second\"" (read-urdf)))
             (write-urdf "third" 0)                       ; written just now: read every time
             (is (search "\"third\"" (read-urdf)))
             (is (not (eq (read-urdf) (read-urdf))))
             (write-urdf "fourth" 0)
             (is (search "\"fourth\"" (read-urdf))))
        (ignore-errors (delete-file path))))))

;;; ---- the master probe and startup without a master --------------------------------------------------

(test ros-master-probe-without-master
  (let* ((uri (format nil "http://127.0.0.1:~d" (free-port)))
         (start (get-internal-real-time)))
    (is-false (roslisp-utilities:ros-available-p :master-uri uri :timeout 1))
    (is (< (seconds-since start) 1.5)))
  (with-env (("ROS_MASTER_URI" "http://127.0.0.1:11999"))
    (is (equal '("http://127.0.0.1:11999" :environment)
               (multiple-value-list (roslisp-utilities:ros-master-uri))))
    (is (equal '("http://10.0.0.1:1" :argument)
               (multiple-value-list (roslisp-utilities:ros-master-uri "http://10.0.0.1:1")))))
  (with-env (("ROS_MASTER_URI" nil))
    (is (eq :default (nth-value 1 (roslisp-utilities:ros-master-uri)))))
  (signals roslisp-utilities:ros-utilities-error
    (roslisp-utilities:ros-available-p :master-uri "localhost:11311"))
  (signals roslisp-utilities:ros-utilities-error
    (roslisp-utilities:ros-available-p :master-uri "http://127.0.0.1:99999"))
  (signals roslisp-utilities:ros-utilities-error
    (roslisp-utilities:ros-available-p :timeout 0)))

(test startup-ros-without-master-names-the-uri
  (let ((roslisp-utilities:*ros-init-functions* '(init-a))
        (uri (format nil "http://127.0.0.1:~d" (free-port))))
    (with-env (("ROS_MASTER_URI" uri))
      (let* ((start (get-internal-real-time))
             (e (handler-case (roslisp-utilities:startup-ros) (error (e) e))))
        (is (< (seconds-since start) 5))
        (is (typep e 'roslisp-utilities:ros-master-unreachable))
        (is (search uri (princ-to-string e)))
        (is (search "ROS_MASTER_URI" (princ-to-string e)))
        (is (string= uri (roslisp-utilities:ros-master-unreachable-uri e)))
        (is (eq :environment (roslisp-utilities:ros-master-unreachable-source e)))))
    (let ((e (handler-case (roslisp-utilities:startup-ros :master-uri uri) (error (e) e))))
      (is (typep e 'roslisp-utilities:ros-master-unreachable))
      (is (search ":MASTER-URI" (princ-to-string e))))
    (is (eq :shutdown (roslisp:node-status)))
    (is-false (roslisp-utilities:belief-state-publisher-running-p)))
  (signals roslisp-utilities:ros-utilities-error (roslisp-utilities:startup-ros :name "9 bad name"))
  (signals roslisp-utilities:ros-utilities-error (roslisp-utilities:startup-ros :publish-rate -1))
  (signals roslisp-utilities:ros-utilities-error (roslisp-utilities:startup-ros :master-uri "ftp://x:1"))
  (is-false (roslisp-utilities:shutdown-ros)))

;;; ---- logging without a node ---------------------------------------------------------------------

(test roslisp-logging-without-node
  (is-false (roslisp-utilities:ros-running-p))
  (let ((out (with-output-to-string (*standard-output*)
               (roslisp:ros-info (roslisp-utilities test) "info ~a" 41)
               (roslisp:ros-warn (roslisp-utilities test) "warn ~a" 42)
               (roslisp:ros-error roslisp-utilities "error ~a" 43)
               (roslisp-utilities:ros-log :warn "through ~a" "ros-log"))))
    (is (search "[(ROSLISP-UTILITIES TEST) INFO]" out))
    (is (search "info 41" out))
    (is (search "[(ROSLISP-UTILITIES TEST) WARN]" out))
    (is (search "warn 42" out))
    (is (search "ERROR]" out))
    (is (search "error 43" out))
    (is (search "[(ROSLISP-UTILITIES) WARN]" out))
    (is (search "through ros-log" out))))

(test light-system-loads-without-roslisp
  ;; a fresh image: roslisp-utilities alone registers init functions and reads the embedded URDF
  ;; without loading roslisp; startup-ros without a master still fails clearly
  (let ((out (uiop:run-program
              (list "sbcl" "--noinform" "--non-interactive" "--no-userinit" "--no-sysinit"
                    "--eval" "(require :asdf)"
                    "--eval" (format nil "(handler-bind ((warning #'muffle-warning)) (asdf:load-asd ~s) (asdf:load-system \"cram-plans/roslisp-utilities\"))"
                                     (namestring (repo-file "cram-plans.asd")))
                    "--eval" "(defun my-init () t)"
                    "--eval" "(roslisp-utilities:register-ros-init-function my-init)"
                    "--eval" "(format t \"~&roslisp:~a~%\" (and (find-package :roslisp) t))"
                    "--eval" "(format t \"~&inits:~a~%\" (roslisp-utilities:ros-init-functions))"
                    "--eval" "(format t \"~&urdf:~a~%\" (length (roslisp-utilities:robot-description-string :fallback-file \"robots/pr2/pr2.urdf\")))"
                    "--eval" (format nil "(format t \"~~&startup:~~a~~%\" (handler-case (roslisp-utilities:startup-ros :master-uri \"http://127.0.0.1:~d\") (error (e) (type-of e))))" (free-port))
                    "--eval" "(format t \"~&roslisp-after:~a~%\" (and (find-package :roslisp) t))")
              :output :string :error-output :output :ignore-error-status t)))
    (is (search "roslisp:NIL" out) "~a" out)
    (is (search "inits:(MY-INIT)" out))
    (is (search (format nil "urdf:~d" (length (uiop:read-file-string (repo-file "robots/pr2/pr2.urdf")))) out))
    (is (search "startup:ROS-MASTER-UNREACHABLE" out))
    (is (search "roslisp-after:NIL" out))))

(test publishing-needs-a-node
  (signals roslisp-utilities:ros-utilities-error (roslisp-utilities:publish-belief-state))
  (signals roslisp-utilities:ros-utilities-error (roslisp-utilities:start-belief-state-publisher :rate 5))
  (is-false (roslisp-utilities:stop-belief-state-publisher)))

;;; ---- the belief state as TF and markers -------------------------------------------------------------

(defun kitchen-world ()
  "A fresh world with a floor, the kitchen, a PR2 at (1, 0.5) turned by 90°, a bottle and a box."
  (let ((w (make-instance 'btr:bt-reasoning-world)))
    (btr:add-object w :static-plane :floor '((0 0 0) (0 0 0 1)))
    (btr:add-object w :urdf :iai-kitchen '((0 0 0) (0 0 0 1))
                    :urdf (uiop:read-file-string (repo-file "resources/iai_kitchen.urdf"))
                    :collision-group :static-filter :collision-mask '(:default-filter))
    (btr:add-object w :urdf :pr2 '((1 0.5 0) (0 0 0.7071067811865476d0 0.7071067811865476d0))
                    :urdf (uiop:read-file-string (repo-file "robots/pr2/pr2.urdf")))
    (btr:set-robot-state-from-joints '(("torso_lift_joint" 0.2) ("l_shoulder_pan_joint" 0.5)
                                       ("l_elbow_flex_joint" -1.0))
                                     (btr:object w :pr2))
    (btr:add-object w :mesh :bottle-1 '((-2 -0.9 0.86) (0 0 0 1)) :mesh :bottle :color '(1 0 0) :mass 0.2)
    (btr:add-object w :box :box-1 '((0 2 1) (0 0 0 1)) :size '(0.1 0.2 0.3) :color '(0 1 0 0.5))
    w))

(defun chain-pose (edges fixed frame)
  "The pose of FRAME in FIXED, composed along the parent edges of EDGES."
  (let ((edge (find frame edges :key #'second :test #'string=)))
    (cond ((string= frame fixed) (cl-transforms:make-identity-transform))
          ((null edge) (error "frame ~s has no parent in the edges" frame))
          (t (cl-transforms:transform* (chain-pose edges fixed (first edge)) (third edge))))))

(defun transform-near-pose-p (transform pose &optional (eps 1d-6))
  (and (< (cl-transforms:v-dist (cl-transforms:translation transform) (cl-transforms:origin pose)) eps)
       (< (cl-transforms:angle-between-quaternions (cl-transforms:rotation transform)
                                                   (cl-transforms:orientation pose))
          1d-5)))

(test belief-state-transforms-compose-to-link-poses
  (let* ((w (kitchen-world))
         (pr2 (btr:object w :pr2))
         (kitchen (btr:object w :iai-kitchen))
         (edges (roslisp-utilities:belief-state-transforms :world w))
         (children (mapcar #'second edges)))
    (is (= (length edges) (+ (length (btr:link-names pr2)) (length (btr:link-names kitchen)) 2)))
    ;; every child frame once: a tree
    (is (= (length children) (length (remove-duplicates children :test #'string=))))
    (is (member "base_footprint" children :test #'string=))
    (is (member "iai_kitchen/sink_area" children :test #'string=))
    (is (member "bottle_1" children :test #'string=))
    (is (not (member "floor" children :test #'string=)))
    (is (equal '("map" "base_footprint")
               (subseq (find "base_footprint" edges :key #'second :test #'string=) 0 2)))
    (dolist (link '("l_gripper_tool_frame" "r_gripper_tool_frame" "head_mount_kinect_rgb_optical_frame"
                    "torso_lift_link" "base_footprint"))
      (when (btr:link-exists-p pr2 link)
        (is (transform-near-pose-p (chain-pose edges "map" link) (btr:link-pose pr2 link))
            "map → ~a composed from the published edges differs from the link pose" link)))
    (is (transform-near-pose-p (chain-pose edges "map" "iai_kitchen/sink_area")
                               (btr:link-pose kitchen "sink_area")))
    (is (transform-near-pose-p (chain-pose edges "map" "bottle_1") (btr:pose (btr:object w :bottle-1))))
    ;; prefixes of the environment
    (let ((roslisp-utilities:*environment-tf-prefix* "kitchen"))
      (is (member "kitchen/sink_area" (mapcar #'second (roslisp-utilities:belief-state-transforms :world w))
                  :test #'string=)))
    (let ((roslisp-utilities:*environment-tf-prefix* nil))
      (is (member "sink_area" (mapcar #'second (roslisp-utilities:belief-state-transforms :world w))
                  :test #'string=)))
    (let ((roslisp-utilities:*environment-tf-prefix* 42))
      (signals roslisp-utilities:ros-utilities-error (roslisp-utilities:belief-state-transforms :world w)))
    (signals roslisp-utilities:ros-utilities-error (roslisp-utilities:belief-state-transforms :world 'kitchen))
    (signals roslisp-utilities:ros-utilities-error
      (roslisp-utilities:belief-state-transforms :world w :fixed-frame ""))
    (btr:destroy-world w)))

(test belief-state-markers-of-items
  (let* ((w (kitchen-world))
         (markers (roslisp-utilities:belief-state-markers :world w))
         (bottle (find :bottle-1 markers :key (lambda (m) (getf m :name))))
         (box (find :box-1 markers :key (lambda (m) (getf m :name)))))
    (is (= 2 (length markers)))
    (is (eq :mesh_resource (getf bottle :type)))
    ;; a file:// URI (rviz needs no ROS_PACKAGE_PATH), or package:// on request
    (is (string= (format nil "file://~a" (namestring (repo-file "resources/meshes/bottle.stl")))
                 (getf bottle :mesh-resource)))
    (let ((roslisp-utilities:*marker-mesh-uris* :package))
      (is (string= "package://cram_plans_resources/meshes/bottle.stl"
                   (getf (find :bottle-1 (roslisp-utilities:belief-state-markers :world w)
                               :key (lambda (m) (getf m :name)))
                         :mesh-resource))))
    (is (equal '(1.0 0.0 0.0 1.0) (getf bottle :color)))
    (is (eq :cube (getf box :type)))
    (is (every (lambda (a b) (< (abs (- a b)) 1d-9)) '(0.1 0.2 0.3) (getf box :scale)))
    (is (equal '(0.0 1.0 0.0 0.5) (getf box :color)))
    (is (/= (getf bottle :id) (getf box :id)))
    ;; ids stay with the names
    (is (= (getf bottle :id)
           (getf (find :bottle-1 (roslisp-utilities:belief-state-markers :world w)
                       :key (lambda (m) (getf m :name)))
                 :id)))
    (btr:destroy-world w)))

(test ensure-ros-home-creates-the-directory
  (let ((dir (format nil "/tmp/cram-ros-home-test-~d/nested" (sb-posix:getpid))))
    (unwind-protect
         (with-env (("ROS_HOME" dir))
           (is (equal (uiop:ensure-directory-pathname dir) (roslisp-utilities:ros-home-directory)))
           (is-false (probe-file (uiop:ensure-directory-pathname dir)))
           (roslisp-utilities:ensure-ros-home)
           (is-true (uiop:directory-exists-p (uiop:ensure-directory-pathname dir)))
           (is-true (uiop:directory-exists-p (format nil "~a/log/" dir))))
      (uiop:delete-directory-tree (uiop:ensure-directory-pathname
                                   (format nil "/tmp/cram-ros-home-test-~d/" (sb-posix:getpid)))
                                  :validate t :if-does-not-exist :ignore)))
  (with-env (("ROS_HOME" nil))
    (is (equal (merge-pathnames ".ros/" (user-homedir-pathname))
               (roslisp-utilities:ros-home-directory)))))

(test ros-load-with-roslisp-loaded
  "ROS-LOAD:LOAD-SYSTEM resolves this project's ROS packages also when roslisp's own loader
(whose ASDF search calls rospack) is loaded, and hands other packages to that loader, whose
error names the package."
  (is (fboundp 'ros-load-manifest::asdf-ros-search))
  (is (string= "cram-plans/cram-pepper-description"
               (ros-load:load-system "cram_pepper_description")))
  (is (string= "cram-plans/cram-pepper-description"
               (ros-load:load-system "cram_pepper_description" :cram-pepper-description)))
  (let ((e (handler-case (progn (ros-load:load-system "no_such_ros_pkg") nil)
             (error (e) e))))
    (is (typep e 'error))
    (is (search "no_such_ros_pkg" (princ-to-string e)))))
