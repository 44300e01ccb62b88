;;;; URDFs from the parameter server, with the project's own model files as the fallback.

(in-package :roslisp-utilities)

(define-condition description-parameter-missing (ros-utilities-error)
  ((parameter :initarg :parameter :reader description-parameter-missing-parameter))
  (:documentation "A URDF was asked for, its parameter could not be read and there is no fallback."))

(defun project-file (path)
  "PATH (a string or pathname) as an absolute pathname; relative ones are taken relative to the
repository root (where cram-plans.asd is)."
  (let ((p (pathname path)))
    (if (uiop:absolute-pathname-p p)
        p
        (asdf:system-relative-pathname "cram-plans/roslisp-utilities" p))))

(defun read-fallback-file (fallback-file parameter why)
  "The text of FALLBACK-FILE and its truename; an error naming it (and PARAMETER, WHY) otherwise."
  (unless (typep fallback-file '(or string pathname))
    (ros-fail ":FALLBACK-FILE ~s for parameter ~a, expected a pathname or a namestring"
              fallback-file parameter))
  (let* ((path (project-file fallback-file))
         (truename (probe-file path)))
    (unless (and truename (not (uiop:directory-pathname-p truename)))
      (ros-fail "Parameter ~a is unavailable (~a) and the fallback file ~a (from ~s) does not exist"
                parameter why path fallback-file))
    (values (fallback-file-text truename) truename)))

(defvar *fallback-texts* '()
  "(truename write-date . text) of the fallback files read last, the latest first: a file is read
again only when it changed. At most *FALLBACK-TEXTS-KEPT*.")

(defparameter *fallback-texts-kept* 8
  "How many fallback files' texts *FALLBACK-TEXTS* keeps.")

(defvar *fallback-texts-lock* (sb-thread:make-mutex :name "fallback texts"))

(defun fallback-file-text (truename)
  "The text of the file TRUENAME, read again only when its write date changed. A write date
counts whole seconds: a file written in the last two seconds is read every time (a change in
the same second would not show), and kept once it is older."
  (let ((date (file-write-date truename)))
    (sb-thread:with-mutex (*fallback-texts-lock*)
      (let ((kept (find-if (lambda (e) (and (equal (first e) truename) (eql (second e) date)))
                           *fallback-texts*)))
        (cond
          (kept (cddr kept))
          ((or (null date) (> date (- (get-universal-time) 2)))
           (uiop:read-file-string truename))
          (t
           (let ((text (uiop:read-file-string truename))
                 (others (remove truename *fallback-texts* :key #'first :test #'equal)))
             (setf *fallback-texts*
                   (cons (list* truename date text)
                         (subseq others 0 (min (length others) (max 0 (1- *fallback-texts-kept*))))))
             text)))))))

(defun check-urdf-text (text source)
  (unless (and (stringp text) (search "<robot" text))
    (ros-fail "~a holds ~a, expected a URDF document (text with a <robot> element)"
              source (if (stringp text)
                         (format nil "a string of ~d characters without <robot>" (length text))
                         (format nil "~s" text))))
  text)

(defun robot-description-string (&key (parameter rob-int:*robot-description-parameter*)
                                      fallback-file)
  "The URDF text in the ROS parameter PARAMETER (by default ROB-INT:*ROBOT-DESCRIPTION-PARAMETER*;
resolved in the node's namespace, so \"robot_description\" is /robot_description) while a node runs (see STARTUP-ROS); when no node
runs, or the parameter is unset, the contents of FALLBACK-FILE (a pathname or namestring;
relative ones are relative to the repository root, e.g. \"robots/pr2/pr2.urdf\").
Returns (values urdf-text source), SOURCE being the parameter's name (a string) or the file's
truename (a pathname). Errors: DESCRIPTION-PARAMETER-MISSING when neither gives a URDF; a
ROS-UTILITIES-ERROR for a missing fallback file or a value that is no URDF document."
  (unless (and (stringp parameter) (plusp (length parameter)))
    (ros-fail "ROBOT-DESCRIPTION-STRING: parameter ~s, expected a non-empty parameter name string"
              parameter))
  (let ((running (ros-running-p)))
    (multiple-value-bind (value present full-name)
        (if running (funcall *parameter-reader* parameter) (values nil nil parameter))
      (cond (present
             (values (check-urdf-text value (format nil "ROS parameter ~a" full-name)) full-name))
            ((null fallback-file)
             (error 'description-parameter-missing
                    :parameter full-name
                    :message (format nil "ROS parameter ~a is unavailable (~:[no ROS node runs; ~
                                          start one with ROSLISP-UTILITIES:STARTUP-ROS~;it is not ~
                                          set on the master~]) and no :FALLBACK-FILE was given"
                                     full-name running)))
            (t
             (let ((why (if running "it is not set on the master" "no ROS node runs")))
               (multiple-value-bind (text truename) (read-fallback-file fallback-file full-name why)
                 (when running
                   (ros-log :info "Parameter ~a is not set; using ~a" full-name truename))
                 (values (check-urdf-text text (namestring truename)) truename))))))))
