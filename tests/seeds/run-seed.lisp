;;;; Replay one seed in this fresh SBCL, the way its reader would start:
;;;;   sbcl --non-interactive --load tests/seeds/run-seed.lisp --eval '(seed-run "000")'
;;;; loads cram-plans as the README says (the checkout on ASDF's central registry), then the
;;;; harness and tests/seeds/seed-NNN.lisp, which replays the page and exits with its verdict.

(require :asdf)
(defvar cl-user::*seed-directory*
  (make-pathname :name nil :type nil :defaults *load-truename*))
(push (merge-pathnames "../../" cl-user::*seed-directory*) asdf:*central-registry*)
(handler-bind ((warning #'muffle-warning))
  (asdf:load-system "cram-plans"))
(require :sb-posix)
(require :sb-bsd-sockets)
(load (merge-pathnames "harness.lisp" cl-user::*seed-directory*))
(load (merge-pathnames "private-ros.lisp" cl-user::*seed-directory*))
(load (merge-pathnames "checks.lisp" cl-user::*seed-directory*))

(defun cl-user::seed-run (number)
  "Replay seed NUMBER (a string such as \"000\")."
  (let ((*package* (find-package "CL-USER")))
    (load (merge-pathnames (format nil "seed-~a.lisp" number) cl-user::*seed-directory*))))
