;;;; Which world STARTUP-ROS builds. Several tutorials register an init function that builds a
;;;; whole belief state (the kitchen with the PR2, the shop with Pepper); with all of them loaded,
;;;; running every one would leave the last one's world. Each such function is declared as the
;;;; init function of a *world*: an environment parameter and the robots it is made for. STARTUP-ROS
;;;; reads the parameter server and runs only the init function of the world it describes (plus
;;;; every init function that builds no world).

(in-package :roslisp-utilities)

(define-condition ros-world-error (ros-utilities-error) ()
  (:documentation "The parameter server describes no registered world, or more than one, or a
world whose init function is not loaded."))

(defstruct (ros-world (:constructor make-ros-world
                          (name init-function environment-parameter robot-names system)))
  "A world STARTUP-ROS can build: its NAME (a keyword), the INIT-FUNCTION that builds it (a
symbol, or a string \"PACKAGE::NAME\" resolved when the package exists), the
ENVIRONMENT-PARAMETER holding its environment URDF, the ROBOT-NAMES (URDF <robot name>s, compared
case-insensitively) it is made for, and the ASDF SYSTEM that defines the init function."
  name init-function environment-parameter robot-names system)

(defvar *ros-worlds* '()
  "The worlds STARTUP-ROS chooses from, in registration order (see REGISTER-ROS-WORLD).")

(defun register-ros-world (name &key init-function environment-parameter robot-names system)
  "Declare the world NAME (a keyword): INIT-FUNCTION (a symbol, or a string \"PACKAGE::NAME\"
for a function of a package that may not be loaded yet) builds it; the parameter server
describes it when ENVIRONMENT-PARAMETER (e.g. \"kitchen_description\") is set, with a
robot_description whose <robot name> is one of ROBOT-NAMES (strings); SYSTEM (a string) is the
ASDF system defining the init function, named in errors. When registered init functions belong to
worlds, STARTUP-ROS runs only the one of the world the parameters describe. Registering NAME again
replaces it in place. Returns NAME."
  (unless (keywordp name)
    (ros-fail "REGISTER-ROS-WORLD: world name ~s, expected a keyword such as :KITCHEN" name))
  (unless (or (and init-function (symbolp init-function))
              (and (stringp init-function) (search "::" init-function)))
    (ros-fail "REGISTER-ROS-WORLD ~s: init function ~s, expected a symbol or a string ~
               \"PACKAGE::NAME\"" name init-function))
  (unless (and (stringp environment-parameter) (plusp (length environment-parameter)))
    (ros-fail "REGISTER-ROS-WORLD ~s: environment parameter ~s, expected a parameter name string"
              name environment-parameter))
  (unless (and (consp robot-names) (every #'stringp robot-names))
    (ros-fail "REGISTER-ROS-WORLD ~s: robot names ~s, expected a list of URDF robot name strings"
              name robot-names))
  (unless (or (null system) (stringp system))
    (ros-fail "REGISTER-ROS-WORLD ~s: system ~s, expected NIL or an ASDF system name string"
              name system))
  (let ((world (make-ros-world name init-function environment-parameter robot-names system))
        (old (position name *ros-worlds* :key #'ros-world-name)))
    (if old
        (setf *ros-worlds* (let ((copy (copy-list *ros-worlds*))) (setf (nth old copy) world) copy))
        (setf *ros-worlds* (append *ros-worlds* (list world)))))
  name)

(defun ros-worlds ()
  "The registered worlds as plists (:name :init-function :environment-parameter :robot-names
:system), in registration order."
  (mapcar (lambda (w)
            (list :name (ros-world-name w) :init-function (ros-world-init-function w)
                  :environment-parameter (ros-world-environment-parameter w)
                  :robot-names (ros-world-robot-names w) :system (ros-world-system w)))
          *ros-worlds*))

(defun find-ros-world (name)
  "The registered world named NAME; an error naming NAME and the known worlds otherwise."
  (or (find name *ros-worlds* :key #'ros-world-name)
      (error 'ros-world-error
             :message (format nil "No ROS world named ~s; the registered worlds are ~{~s~^, ~}"
                              name (mapcar #'ros-world-name *ros-worlds*)))))

(defun world-init-symbol (world)
  "The symbol of WORLD's init function, or NIL while its package does not exist."
  (let ((f (ros-world-init-function world)))
    (if (symbolp f)
        f
        (let* ((at (search "::" f))
               (package (find-package (subseq f 0 at))))
          (and package (find-symbol (subseq f (+ at 2)) package))))))

(defun init-function-world (name)
  "The registered world whose init function is NAME, or NIL."
  (find-if (lambda (w) (let ((s (world-init-symbol w))) (and s (eq s name)))) *ros-worlds*))

(defun urdf-robot-name (text)
  "The name attribute of the <robot> element of the URDF TEXT, or NIL."
  (let ((start (and (stringp text)
                    (loop for p = (search "<robot" text) then (search "<robot" text :start2 (1+ p))
                          while p
                          when (and (< (+ p 6) (length text))
                                    (member (char text (+ p 6)) '(#\Space #\Tab #\Newline #\Return)))
                            return p))))
    (when start
      (let* ((end (position #\> text :start start))
             (at (search "name=" text :start2 start :end2 end)))
        (when at
          (let* ((q (char text (+ at 5)))
                 (close (position q text :start (+ at 6) :end end)))
            (and (member q '(#\" #\')) close (subseq text (+ at 6) close))))))))

(defun world-robot-p (world robot-name)
  (member robot-name (ros-world-robot-names world) :test #'string-equal))

(defun describe-world (world)
  (format nil "~s (~a with robot ~{~a~^ or ~})" (ros-world-name world)
          (ros-world-environment-parameter world) (ros-world-robot-names world)))

(defun parameter-world (parameter-reader)
  "The registered world the parameters read through PARAMETER-READER (a function of a parameter
name returning (values value present-p full-name)) describe, and a text saying why; NIL when no
description parameter is set at all. Errors (ROS-WORLD-ERROR) when the parameters contradict
every world, or fit several."
  (multiple-value-bind (robot-urdf robot-present robot-param) (funcall parameter-reader rob-int:*robot-description-parameter*)
    (let* ((robot (and robot-present (urdf-robot-name robot-urdf)))
           (environments (remove-if-not (lambda (w)
                                          (nth-value 1 (funcall parameter-reader
                                                                (ros-world-environment-parameter w))))
                                        *ros-worlds*))
           (fitting (if robot
                        (remove-if-not (lambda (w) (world-robot-p w robot))
                                       (or environments *ros-worlds*))
                        environments)))
      (flet ((fail (fmt &rest args)
               (error 'ros-world-error
                      :message (format nil "~?~%The registered worlds: ~{~a~^; ~}. Choose one with ~
                                            (roslisp-utilities:startup-ros :world NAME)."
                                       fmt args (mapcar #'describe-world *ros-worlds*)))))
        (cond ((and (null environments) (not robot-present)) nil)
              ((and robot-present (null robot))
               (fail "The parameter ~a holds no URDF <robot name=...>." robot-param))
              ((= 1 (length fitting))
               (values (first fitting)
                       (format nil "~:[no environment parameter is set~;~:*~{~a~^ and ~} set~]~
                                    ~@[, robot ~s in ~a~]"
                               (mapcar #'ros-world-environment-parameter environments)
                               robot robot-param)))
              ((null fitting)
               (fail "The ROS parameters match no world: ~:[no environment parameter is set~;~:*~
                      ~{~a~^ and ~} set~], and ~a describes the robot ~s."
                     (mapcar #'ros-world-environment-parameter environments) robot-param robot))
              (t
               (fail "The ROS parameters fit several worlds (~{~s~^, ~}): ~{~a~^ and ~} set~@[, ~
                      robot ~s~]."
                     (mapcar #'ros-world-name fitting)
                     (mapcar #'ros-world-environment-parameter environments) robot)))))))

(defun select-init-functions (names parameter-reader &key world)
  "The init function names of NAMES (in order) that STARTUP-ROS runs, and the world chosen.
Names that build no registered world always run. Of the world-building ones, only the init
function of WORLD (a world name) runs when it is given, else that of the world the parameters
(read through PARAMETER-READER, see PARAMETER-WORLD) describe; when no description parameter
is set, the first registered one runs (its world comes from the project's files) and a warning
says so. Errors when the described world's init function is not among NAMES."
  (let* ((world-names (remove-if-not #'init-function-world names))
         (chosen (and world (find-ros-world world)))
         (why (and world "chosen with :WORLD")))
    (when (and (null world-names) (null chosen))
      (return-from select-init-functions (values names nil)))
    (unless chosen
      (multiple-value-setq (chosen why) (parameter-world parameter-reader)))
    (unless chosen
      (setf chosen (init-function-world (first world-names)))
      (ros-log :warn "No robot_description and no environment parameter (~{~a~^, ~}) on the ~
                      master; building the ~s world from the project's files."
               (mapcar #'ros-world-environment-parameter *ros-worlds*) (ros-world-name chosen))
      (setf why "the first registered world; no description parameter is set"))
    (let ((init (world-init-symbol chosen)))
      (unless (and init (member init names))
        (error 'ros-world-error
               :message (format nil "The ROS parameters describe the world ~a (~a), but its init ~
                                     function ~a is ~:[not loaded~;not registered~]~@[; load it ~
                                     with (asdf:load-system ~s)~]."
                                (describe-world chosen) why
                                (or init (ros-world-init-function chosen)) init
                                (ros-world-system chosen))))
      (let ((skipped (remove init world-names)))
        (ros-log :info "Building the ~(~a~) world (~a): ~s~@[; not running ~{~s~^, ~}~]"
                 (ros-world-name chosen) why init skipped)
        (values (remove-if (lambda (n) (member n skipped)) names) (ros-world-name chosen))))))

;;; The tutorials' worlds (their packages load after this file).

(register-ros-world :kitchen
                    :init-function "CRAM-BULLET-WORLD-TUTORIAL::INIT-PROJECTION"
                    :environment-parameter "kitchen_description"
                    :robot-names '("pr2")
                    :system "cram-plans/cram-bullet-world-tutorial")

(register-ros-world :shop
                    :init-function "CRAM-PEPPER-DEMO::INIT-PROJECTION"
                    :environment-parameter "shelf_description"
                    :robot-names '("pepper" "JulietteY20MP")
                    :system "cram-plans/cram-pepper-demo")
