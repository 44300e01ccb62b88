;;;; Package CRAM-LANGUAGE (nicknames CPL and CPL-IMPL): the plan language.

(defpackage :cram-language
  (:nicknames :cpl :cpl-impl)
  (:use :cl)
  (:shadow #:sleep)
  (:export
   ;; tasks and plan macros
   #:top-level #:named-top-level #:seq #:par #:pursue #:try-all
   #:try-in-order #:try-each-in-order
   #:def-cram-function #:def-top-level-cram-function #:declare-goal #:def-goal
   #:*current-task* #:task #:task-name #:task-status #:task-parent
   #:current-task-p #:*inherited-specials* #:with-evaporation-deferred
   #:not-inside-plan-error #:nested-top-level-error
   #:task-exit-error #:task-exit-task-name
   ;; failures
   #:plan-failure #:simple-plan-failure #:composite-failure #:composite-failures
   #:common-lisp-error-envelope #:envelop-error
   #:fail #:with-failure-handling #:retry
   #:with-retry-counters #:do-retry #:get-counter #:reset-counter
   ;; fluents
   #:fluent #:value-fluent #:fluent-net #:make-fluent #:fluent-name #:value
   #:wait-for #:whenever #:pulse #:pulsed #:fl-funcall #:fl-apply
   #:fl-and #:fl-or #:fl-not #:fl< #:fl> #:fl= #:fl<= #:fl>= #:fl-eq #:fl-eql
   #:fl+ #:fl- #:fl* #:fl/
   ;; time
   #:sleep #:*sleep-function* #:unix-time
   ;; task tree
   #:task-tree-node #:with-task-tree-node #:*task-tree-node*
   #:*last-task-tree* #:task-tree-to-json #:write-task-tree-html
   #:node-kind #:node-name #:node-designator #:node-children #:node-parent
   #:node-outcome #:node-failure #:node-caught-failures #:node-retries
   #:node-start-time #:node-end-time #:node-start-unix #:node-end-unix
   #:node-duration #:find-task-tree-nodes #:node-pictures #:note-picture
   ;; logging
   #:log-message #:log-debug #:log-info #:log-warn #:log-error
   #:*log-stream* #:*log-tags* #:*log-level* #:*log-tally* #:with-log-tags))
