;;;; Which world STARTUP-ROS builds: the choice from the parameter server (no master needed, the
;;;; parameters come from a table), and live, a fresh SBCL that loads cram-plans through the
;;;; central registry alone and runs STARTUP-ROS under launch/world.launch (then move-bottle) and
;;;; under launch/pepper.launch.

(in-package :cram-plans-tests-ros)

(in-suite ros)

(defvar *world-calls* '())
(defun world-init-a () (push :a *world-calls*))
(defun world-init-b () (push :b *world-calls*))
(defun plain-init () (push :plain *world-calls*))

(defun parameter-table-reader (alist)
  "A parameter reader (see ROSLISP-UTILITIES::PARAMETER-WORLD) answering from ALIST."
  (lambda (name)
    (let ((entry (assoc name alist :test #'string=)))
      (values (cdr entry) (and entry t) (format nil "/~a" name)))))

(defmacro with-test-worlds (&body body)
  `(let ((roslisp-utilities::*ros-worlds* '()))
     (roslisp-utilities:register-ros-world :a :init-function 'world-init-a
                                              :environment-parameter "a_description"
                                              :robot-names '("ra" "ra2") :system "sys-a")
     (roslisp-utilities:register-ros-world :b :init-function "CRAM-PLANS-TESTS-ROS::WORLD-INIT-B"
                                              :environment-parameter "b_description"
                                              :robot-names '("rb"))
     ,@body))

(defun select (names alist &rest keys)
  (apply #'roslisp-utilities:select-init-functions names (parameter-table-reader alist) keys))

(test ros-world-choice-from-parameters
  (with-test-worlds
    (let ((names '(plain-init world-init-a world-init-b))
          (urdf-a "<robot name=\"RA\"><link name=\"x\"/></robot>")
          (urdf-b "<?xml version=\"1.0\"?>
<robot  name='rb' xmlns:xacro=\"x\"><link name=\"y\"/></robot>"))
      ;; the environment parameter and the robot decide; plain init functions always run
      (is (equal '(plain-init world-init-a)
                 (select names `(("a_description" . "<robot name=\"e\"/>") ("robot_description" . ,urdf-a)))))
      (is (equal '(plain-init world-init-b)
                 (select names `(("b_description" . "e") ("robot_description" . ,urdf-b)))))
      (is (eq :b (nth-value 1 (select names `(("b_description" . "e") ("robot_description" . ,urdf-b))))))
      ;; both environments set (two launch files on one master): the robot decides
      (is (equal '(plain-init world-init-b)
                 (select names `(("a_description" . "e") ("b_description" . "e")
                                 ("robot_description" . ,urdf-b)))))
      ;; only the environment, or only the robot
      (is (equal '(plain-init world-init-a) (select names '(("a_description" . "e")))))
      (is (equal '(plain-init world-init-b) (select names `(("robot_description" . ,urdf-b)))))
      ;; :world overrides the parameters
      (is (equal '(plain-init world-init-a)
                 (select names `(("robot_description" . ,urdf-b)) :world :a)))
      ;; nothing on the master: the first registered world, with a warning
      (let ((out (with-output-to-string (*standard-output*)
                   (is (equal '(plain-init world-init-a) (select names '()))))))
        (is (search "No robot_description and no environment parameter" out) "~a" out))
      ;; no world functions registered: everything runs, nothing is read
      (is (equal '(plain-init) (roslisp-utilities:select-init-functions
                                '(plain-init) (lambda (n) (error "read ~a" n))))))))

(test ros-world-choice-errors-name-the-values
  (with-test-worlds
    (let ((names '(world-init-a world-init-b)))
      (flet ((message (alist &rest keys)
               (handler-case (progn (apply #'select names alist keys) nil)
                 (roslisp-utilities:ros-world-error (e) (princ-to-string e)))))
        ;; a robot no world knows
        (let ((m (message '(("a_description" . "e") ("robot_description" . "<robot name=\"zz\"/>")))))
          (is (search "\"zz\"" m) "~a" m)
          (is (search "a_description" m))
          (is (search "startup-ros :world" m)))
        ;; several worlds fit
        (let ((m (message '(("a_description" . "e") ("b_description" . "e")))))
          (is (search "several worlds" m) "~a" m))
        ;; a robot_description without a robot name
        (is (search "no URDF <robot" (message '(("robot_description" . "hello")))))
        ;; the described world's init function is not registered
        (let ((m (handler-case (progn (select '(world-init-a) '(("b_description" . "e"))) nil)
                   (roslisp-utilities:ros-world-error (e) (princ-to-string e)))))
          (is (search "WORLD-INIT-B" m) "~a" m)
          (is (search "not registered" m))))
      (signals roslisp-utilities:ros-world-error (select names '() :world :nope))
      (signals roslisp-utilities:ros-utilities-error
        (roslisp-utilities:register-ros-world "a" :init-function 'x :environment-parameter "p"
                                                  :robot-names '("r")))
      (signals roslisp-utilities:ros-utilities-error
        (roslisp-utilities:register-ros-world :c :init-function 'x :environment-parameter "p"
                                                 :robot-names "r"))
      (signals roslisp-utilities:ros-utilities-error
        (roslisp-utilities:startup-ros :world :nope)))))

(test tutorial-worlds-are-registered
  (let ((worlds (roslisp-utilities:ros-worlds)))
    (is (equal "kitchen_description"
               (getf (find :kitchen worlds :key (lambda (w) (getf w :name))) :environment-parameter)))
    (is (equal "shelf_description"
               (getf (find :shop worlds :key (lambda (w) (getf w :name))) :environment-parameter)))))

;;; ---- live: a fresh SBCL under each launch file ------------------------------------------------------

(defun fresh-sbcl-under-ros (seconds &rest forms)
  "Run a fresh SBCL in the private ROS environment, without CL_SOURCE_REGISTRY, that loads
cram-plans through ASDF's central registry and evaluates FORMS (strings); (values exit-code output)."
  (let ((*ros* (copy-private-ros *ros*)))
    (setf (private-ros-env *ros*)
          (remove-if (lambda (e) (uiop:string-prefix-p "CL_SOURCE_REGISTRY=" e)) (private-ros-env *ros*)))
    (apply #'run-with-timeout seconds "sbcl" "--noinform" "--non-interactive" "--no-userinit"
           "--no-sysinit" "--eval" "(require :asdf)"
           "--eval" (format nil "(push ~s asdf:*central-registry*)"
                            (namestring (asdf:system-source-directory "cram-plans")))
           "--eval" "(asdf:load-system \"cram-plans\")"
           (loop for f in forms append (list "--eval" f)))))

(test live-startup-ros-builds-the-launched-world
  (let ((left :not-run))
    (setf left
          (call-with-private-ros
           (lambda ()
             (let ((world (roslaunch "world" "launch/world.launch")))
               (multiple-value-bind (code out)
                   (fresh-sbcl-under-ros
                    240 "(roslisp-utilities:startup-ros)"
                    "(format t \"~&WORLD ~s ~s ~s~%\" btr:*environment-name* rob-int:*robot-name*
                       (and (btr:object btr:*current-bullet-world* :iai-kitchen)
                            (btr:link-exists-p (btr:object btr:*current-bullet-world* :iai-kitchen)
                                               \"iai_fridge_door_handle\")))"
                    "(format t \"~&MOVED ~a~%\" (and (btw-tut:move-bottle) t))"
                    "(roslisp-utilities:shutdown-ros)")
                 (is (eql 0 code) "world.launch: fresh SBCL failed:~%~a" out)
                 (is (search "Building the kitchen world" out) "~a" out)
                 (is (search "WORLD :IAI-KITCHEN :PR2 T" out) "~a" out)
                 (is (search "MOVED T" out) "~a" out))
               (stop-process world)
               (setf (private-ros-processes *ros*) (remove world (private-ros-processes *ros*))))
             ;; kitchen_description stays on the master; Pepper's robot_description decides
             (roslaunch "pepper" "launch/pepper.launch" "robot_tf:=false")
             (multiple-value-bind (code out)
                 (fresh-sbcl-under-ros
                  180 "(roslisp-utilities:startup-ros)"
                  "(format t \"~&WORLD ~s ~a ~s~%\" btr:*environment-name* rob-int:*robot-name*
                     (btr:link-exists-p (btr:object btr:*current-bullet-world* :kitchen)
                                        \"shelf_1_level_3_link\"))"
                  "(roslisp-utilities:shutdown-ros)")
               (is (eql 0 code) "pepper.launch: fresh SBCL failed:~%~a" out)
               (is (search "Building the shop world" out) "~a" out)
               (is (search "WORLD :KITCHEN PEPPER T" out) "~a" out)))))
    (is (null left) "processes left running after the test: ~s" left)))
