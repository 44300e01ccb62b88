;;;; Designator benchmarks: building and referencing an action designator through 50
;;;; ACTION-GROUNDING rules, against the same rules run by SWI-Prolog in the same run; and
;;;; performing a motion through a process module.

(require :asdf)
(asdf:load-asd (merge-pathnames "../../cram-plans.asd" *load-truename*))
(asdf:load-system "cram-plans/cram-executive")

(defpackage :cram-bench.designators
  (:use :cl :cram-bench))

(in-package :cram-bench.designators)

(defparameter *rule-count* 50 "How many action types the grounding rules cover.")

(defun bench-plan (&rest arguments)
  "The plan every benchmark grounding names."
  arguments)

(defun install-grounding-rules ()
  "Define one ACTION-GROUNDING rule per action type :BENCH-ACTION-i, i below *RULE-COUNT*."
  (eval `(prolog:def-fact-group designators-bench-groundings (desig:action-grounding)
           ,@(loop for i below *rule-count*
                   collect `(prolog:<- (desig:action-grounding ?d (bench-plan ?d ?arm))
                              (desig:desig-prop ?d (:type ,(intern (format nil "BENCH-ACTION-~d" i)
                                                                   :keyword)))
                              (desig:desig-prop ?d (:arm ?arm)))))))

(defun swi-program ()
  "50 clauses written out, as the Lisp side has them."
  (with-output-to-string (s)
    (loop for i below *rule-count*
          do (format s "action_grounding(D, plan(D, Arm)) :- member(type-bench_action_~d, D), ~
                        member(arm-Arm, D).~%" i))
    (format s "loop(0) :- !.~%loop(N) :- D = [type-bench_action_~d, arm-left], ~
               once(action_grounding(D, _)), N1 is N - 1, loop(N1).~%" (1- *rule-count*))
    (format s "main :- N = 200000, statistics(cputime, T0), loop(N), statistics(cputime, T1), ~
               T is (T1 - T0) / N, format('~~15e~~n', [T]), halt.~%")))

(defun swi-time ()
  "Seconds per first-solution grounding query in SWI-Prolog, or NIL when it cannot run."
  (let ((file (merge-pathnames "cram-bench-designators.pl" (uiop:temporary-directory))))
    (with-open-file (s file :direction :output :if-exists :supersede)
      (write-string (swi-program) s))
    (let ((out (run-peer "swipl" "-q" "-g" "main" "-t" "halt" (namestring file))))
      (and out (ignore-errors (float (read-from-string out) 1d0))))))

(cpm:def-process-module bench-pm (motion)
  (desig:reference motion))

(prolog:def-fact-group designators-bench-motions (desig:motion-grounding
                                                  cpm:matching-process-module)
  (prolog:<- (desig:motion-grounding ?d (bench-move ?x))
    (desig:desig-prop ?d (:type :bench-moving))
    (desig:desig-prop ?d (:target ?x)))
  (prolog:<- (cpm:matching-process-module ?d bench-pm)
    (desig:desig-prop ?d (:type :bench-moving))))

(define-benchmark designators ()
  (install-grounding-rules)
  (let* ((sink nil)
         (ours (time-per-call
                (lambda ()
                  (setf sink (desig:reference
                              (desig:an action (type bench-action-49) (arm left)))))))
         (peer (swi-time)))
    (add-row "build + reference an action designator (50 grounding rules)"
             (format-seconds ours)
             :peer-name "SWI-Prolog (same rules, first solution)"
             :peer (and peer (format-seconds peer))
             :ratio (and peer (/ ours peer))))
  (let* ((?target 1)
         (sink nil)
         (ours (cpm:with-process-modules-running (bench-pm)
                 (time-per-call
                  (lambda ()
                    (setf sink (exe:perform (desig:a motion (type bench-moving)
                                                            (target ?target)))))))))
    (add-row "perform a motion through a process module" (format-seconds ours))))
