;;;; Package CRAM-LANGUAGE-IMPLEMENTATION (nickname CPL-IMPL): CRAM splits its plan language
;;;; into an implementation package and CPL; code written for CRAM names some symbols through
;;;; CPL-IMPL (CPL-IMPL:*DEBUG-ON-LISP-ERRORS*, CPL-IMPL:TOP-LEVEL ...). Here it holds no code of
;;;; its own: it exports CPL's very symbols under CRAM's implementation names, so
;;;; (eq 'cpl-impl:fail 'cpl:fail).

(in-package :cl-user)

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defparameter cram-language::+implementation-names+
    '(;; tasks and plan macros
      "TOP-LEVEL" "SEQ" "PAR" "PURSUE" "TRY-ALL" "TRY-IN-ORDER" "TRY-EACH-IN-ORDER" "PAR-LOOP"
      "PARTIAL-ORDER" "TAG" "WITH-TAGS" "WITH-TASK-SUSPENDED" "TAGGED"
      "DEF-CRAM-FUNCTION" "DEF-TOP-LEVEL-CRAM-FUNCTION" "DEF-TOP-LEVEL-PLAN" "DEF-PLAN"
      "GET-TOP-LEVEL-TASK-TREE" "DECLARE-GOAL" "DEF-GOAL" "GOAL" "REGISTER-GOAL" "GOAL-CONTEXT"
      "SUCCEED" "DESCRIBE-GOAL"
      "*CURRENT-TASK*" "*CURRENT-PATH*" "CURRENT-TASK" "TASK" "TOPLEVEL-TASK" "TASK-ALIVE"
      "TASK-DEAD" "TASK-RUNNING-P" "TASK-DEAD-P" "TASK-DONE-P" "TASK-FAILED-P" "STATUS"
      "RESULT" "EVAPORATE" "SUSPEND" "WAKE-UP" "JOIN-TASK" "TASK-PATH" "WITHOUT-SCHEDULING"
      "WITH-SCHEDULING" "NAME" "SLEEP*"
      ;; failures and the debugger
      "FAIL" "ON-FAIL" "SIMPLE-PLAN-FAILURE" "PLAN-FAILURE" "WITH-FAILURE-HANDLING" "RETRY"
      "WITH-RETRY-COUNTERS" "DO-RETRY" "RESET-COUNTER" "GET-COUNTER"
      "COMMON-LISP-ERROR-ENVELOPE" "ENVELOP-ERROR" "COMPOSITE-FAILURE" "COMPOSITE-FAILURES"
      "*BREAK-ON-PLAN-FAILURES*" "*DEBUG-ON-LISP-ERRORS*"
      ;; fluents
      "FLUENT" "VALUE-FLUENT" "VALUE" "PEEK-VALUE" "WAIT-FOR" "PULSE" "WHENEVER" "MAKE-FLUENT"
      "FL<" "FL>" "FL=" "FL+" "FL-" "FL*" "FL/" "FL-EQ" "FL-EQL" "FL-NOT" "FL-AND" "FL-OR"
      "FL-PULSED" "FL-FUNCALL" "FL-APPLY" "FL-VALUE-CHANGED"
      ;; task tree
      "TASK-TREE-NODE" "TASK-TREE-NODE-P" "TASK-TREE-NODE-PATH" "TASK-TREE-NODE-CODE"
      "TASK-TREE-NODE-PARENT" "TASK-TREE-NODE-CHILDREN" "WITH-TASK-TREE-NODE"
      "MAKE-TASK-TREE-NODE" "*TASK-TREE*" "FLATTEN-TASK-TREE"
      ;; logging
      "*LOG-OUTPUT*" "LOG-ENABLE" "LOG-DISABLE" "LOG-SET")
    "The names CRAM's CRAM-LANGUAGE-IMPLEMENTATION package exports. Those that CPL exports too
are exported by CPL-IMPL as CPL's symbols.")

  ;; made once: evaluated again (loading what was just compiled), DEFPACKAGE would find the
  ;; exports below missing from its own list and warn about them
  (unless (find-package :cram-language-implementation)
    (defpackage :cram-language-implementation
      (:nicknames :cpl-impl)
      (:use)
      (:documentation "CRAM's implementation package of the plan language: the symbols of CPL
\(CRAM-LANGUAGE) under the names CRAM's CPL-IMPL exports, e.g. CPL-IMPL:*DEBUG-ON-LISP-ERRORS*.")))

  (let ((implementation (find-package :cram-language-implementation)))
    (dolist (name cram-language::+implementation-names+)
      (multiple-value-bind (symbol status) (find-symbol name :cram-language)
        (when (eq status :external)
          (import symbol implementation)
          (export symbol implementation))))))
