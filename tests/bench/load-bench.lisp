;;;; Warm load time of the whole system in a fresh SBCL (fasls already compiled).

(in-package :cram-bench)

(defparameter *cram-plans-asd* (namestring (merge-pathnames "../../cram-plans.asd" *load-truename*))
  "The system definition file of cram-plans.")

(define-benchmark warm-load ()
  (let* ((asd *cram-plans-asd*)
         (form (format nil "(handler-bind ((warning #'muffle-warning)) (asdf:load-asd ~s) (asdf:load-system \"cram-plans\") (princ :loaded))" asd))
         (args (list "--noinform" "--non-interactive" "--no-userinit" "--no-sysinit"
                     "--eval" "(require :asdf)" "--eval" form))
         (empty (list "--noinform" "--non-interactive" "--no-userinit" "--no-sysinit" "--eval" "(require :asdf)")))
    ;; the first run compiles whatever is stale, and must succeed
    (unless (search "LOADED" (or (apply #'run-peer "sbcl" args) ""))
      (error "loading cram-plans in a fresh SBCL failed"))
    (let ((full (median-seconds (lambda () (apply #'run-peer "sbcl" args)) :runs 3 :warmup 0))
          (bare (median-seconds (lambda () (apply #'run-peer "sbcl" empty)) :runs 3 :warmup 0)))
      (add-row "warm load of cram-plans in a fresh SBCL" (format-seconds full)
               :peer-name "SBCL start + ASDF alone" :peer (format-seconds bare)
               :ratio (/ full bare) :goal "<= 2 s" :met (<= full 2d0)))))
