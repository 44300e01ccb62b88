;;;; Load every test system and run suite ALL in this fresh SBCL.
;;;; Exit status 0 only when no check failed.

(require :asdf)
(handler-bind ((warning #'muffle-warning))
  (asdf:load-asd (merge-pathnames "../cram-plans.asd" *load-truename*))
  (asdf:load-system "cram-plans/tests"))
(uiop:quit (if (uiop:symbol-call :cram-plans-tests :run-all) 0 1))
